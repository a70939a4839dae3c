// The phases of one axis: pre-move, seek, stop, back-off, re-approach, index,
// pull-off, assign, final move; their bounds; the configuration check; the
// trigger position and home correction.
#include <catch2/catch.hpp>

#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

SCENARIO("pre-move none: seeking starts at once", "[phases][pre_move]") {
  Rig r;
  r.settings.axes[0].pre_move_mode = PreMove::none;
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK_FALSE(r.saw(0, Phase::pre_move));
  CHECK(r.trace[0].max_actual == Approx(100));
}

SCENARIO("pre-move always: moves the pre-move distance away from the sensor first", "[phases][pre_move]") {
  Rig r;
  r.settings.axes[0].pre_move_mode = PreMove::always;
  r.settings.axes[0].pre_move_distance_mm = 5;
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK(r.saw(0, Phase::pre_move));
  CHECK(r.trace[0].max_actual == Approx(105).margin(1e-9));
  CHECK(r.actual(0) == Approx(1.05).margin(1e-4));
}

SCENARIO("pre-move only if the sensor is active", "[phases][pre_move]") {
  Rig r;
  r.settings.axes[0].pre_move_mode = PreMove::if_sensor_active;
  r.settings.axes[0].pre_move_distance_mm = 5;
  GIVEN("the sensor is inactive at start") {
    r.clear_trace();
    REQUIRE(r.home_all());
    THEN("no pre-move") {
      CHECK_FALSE(r.saw(0, Phase::pre_move));
      CHECK(r.trace[0].max_actual == Approx(100));
    }
  }
  GIVEN("the carriage starts on the sensor") {
    r.machine.axes[0].actual_position_mm = -0.5;
    r.step();
    REQUIRE(r.axis(0).sensor);
    r.clear_trace();
    REQUIRE(r.home_all());
    THEN("it moves off the sensor by the distance, then seeks and stops on it normally") {
      CHECK(r.saw(0, Phase::pre_move));
      CHECK(r.trace[0].max_actual == Approx(4.5).margin(1e-9));
      CHECK(r.saw(0, Phase::seek));
      CHECK(r.saw(0, Phase::stop));
      CHECK(r.actual(0) == Approx(1.05).margin(1e-4));
    }
  }
}

SCENARIO("the published stop distance is the seek's v^2/2a plus its travel while debouncing", "[phases][stop]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.seek_feedrate_mm_per_min = 1200;  // 20 mm/s
  s.acceleration_mm_per_s2 = 500;
  s.debounce_ms = 5;
  r.step();
  // 20^2 / (2 * 500) = 0.4 mm, and 20 mm/s * 5 ms = 0.1 mm: what max_stop_distance is checked against.
  CHECK(r.axis(0).stop_distance_mm == Approx(0.5).margin(1e-12));
  CHECK(r.axis(0).stop_distance_mm == Approx(seek_stop_distance_mm(s)).margin(1e-12));
}

SCENARIO("switch already active at start goes straight to back-off", "[phases]") {
  Rig r;
  r.machine.axes[0].actual_position_mm = -0.5;
  r.step();
  REQUIRE(r.axis(0).sensor);
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK_FALSE(r.saw(0, Phase::stop));
  CHECK(r.saw(0, Phase::back_off));
  // It never moved toward the sensor.
  CHECK(r.trace[0].min_actual == Approx(-0.5));
  CHECK(r.actual(0) == Approx(1.05).margin(1e-4));
  CHECK(r.axis(0).position_mm == Approx(0).margin(1e-9));
}

SCENARIO("the stop after the trigger ends within the stopping distance with the sensor still active",
         "[phases][stop]") {
  Rig r;
  double rest_after_stop = 0;
  r.on_period = [&](const Rig& rr) {
    if (rr.axis(0).phase == Phase::stop) {
      CHECK(rr.axis(0).sensor);
      rest_after_stop = rr.simulator->actual_position_mm(0);
    }
  };
  REQUIRE(r.home_all());
  const AxisSettings& s = r.settings.axes[0];
  const double v = mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min);
  // Trigger at 0; stopped within v²/2a plus one period of travel (the trigger is seen at the period's end).
  CHECK(-rest_after_stop <= stop_distance_mm(v, s.acceleration_mm_per_s2) + v * r.dt_s + 1e-9);
  CHECK(-rest_after_stop >= stop_distance_mm(v, s.acceleration_mm_per_s2) - 1e-9);
}

SCENARIO("trigger position and home correction are recorded per axis", "[phases][correction]") {
  Rig r;
  REQUIRE(r.home_all());
  GIVEN("a second homing with no lost steps") {
    r.move(0, 50);
    r.run_until([&] { return !r.any_moving() && r.axis(0).phase == Phase::idle; }, 30);
    REQUIRE(r.home_all());
    THEN("the correction is zero within the edge tolerance, the trigger is the edge's machine coordinate") {
      const double tol = edge_tolerance_mm(r.settings.axes[0], r.dt_s);
      CHECK(r.axis(0).home_correction_mm == Approx(0).margin(tol));
      // The release edge lies at carriage 0.05 = machine 0.05 - 1.05 = -1.
      CHECK(r.axis(0).trigger_position_mm == Approx(-1).margin(tol));
    }
  }
  GIVEN("steps lost between two homings") {
    for (double lost : {0.3, -0.7, 2.25}) {
      DYNAMIC_SECTION("lost " << lost << " mm") {
        r.move(0, 50);
        r.run_until([&] { return !r.any_moving() && r.axis(0).phase == Phase::idle; }, 30);
        r.sim().lose_steps(0, lost);
        REQUIRE(r.home_all());
        const double tol = edge_tolerance_mm(r.settings.axes[0], r.dt_s);
        THEN("home correction equals the injected lost steps") {
          CHECK(r.axis(0).home_correction_mm == Approx(lost).margin(tol));
          CHECK(r.axis(0).trigger_position_mm == Approx(-1 - lost).margin(tol));
          CHECK(r.actual(0) == Approx(1.05).margin(tol));
        }
      }
    }
  }
}

SCENARIO("the configuration check refuses before any motion and names the setting", "[phases][settings]") {
  struct Case {
    const char* what;
    std::function<void(Settings&)> spoil;
    const char* name;
  };
  const std::vector<Case> cases{
      {"stop distance beyond max_stop_distance",
       [](Settings& s) { s.axes[0].max_stop_distance_mm = 0.1; }, "axis.x.max_stop_distance"},
      {"latch not slower than seek",
       [](Settings& s) { s.axes[0].latch_feedrate_mm_per_min = 1200; }, "axis.x.latch_feedrate"},
      {"zero seek feedrate", [](Settings& s) { s.axes[0].seek_feedrate_mm_per_min = 0; }, "axis.x.seek_feedrate"},
      {"zero acceleration", [](Settings& s) { s.axes[0].acceleration_mm_per_s2 = 0; }, "axis.x.acceleration"},
      {"zero max seek travel", [](Settings& s) { s.axes[0].max_seek_travel_mm = 0; }, "axis.x.max_seek_travel"},
      {"zero max back-off", [](Settings& s) { s.axes[0].max_backoff_mm = 0; }, "axis.x.max_backoff"},
      {"negative pull-off", [](Settings& s) { s.axes[0].pull_off_mm = -1; }, "axis.x.pull_off"},
      {"pre-move without distance",
       [](Settings& s) {
         s.axes[0].pre_move_mode = PreMove::always;
         s.axes[0].pre_move_distance_mm = 0;
       },
       "axis.x.pre_move_distance"},
      {"pushing without push distance",
       [](Settings& s) {
         s.axes[0].mode = HomingMode::pushing_release;
         s.axes[0].push_distance_mm = 0;
       },
       "axis.x.push_distance"},
      {"index without pitch",
       [](Settings& s) {
         s.axes[0].mode = HomingMode::switch_index;
         s.axes[0].index_pitch_mm = 0;
       },
       "axis.x.index_pitch"},
      {"home position outside the soft limits",
       [](Settings& s) {
         s.axes[0].soft_limits_enable = true;
         s.axes[0].home_position_mm = -50;
       },
       "axis.x.home_position"},
      {"inverted soft limits",
       [](Settings& s) {
         s.axes[0].soft_limits_enable = true;
         s.axes[0].soft_limit_min_mm = 600;
       },
       "soft_limit_min"},
      {"final position outside the soft limits",
       [](Settings& s) {
         s.axes[0].soft_limits_enable = true;
         s.axes[0].final_move_enable = true;
         s.axes[0].final_position_mm = 900;
       },
       "axis.x.final_position"},
      {"slave of itself",
       [](Settings& s) {
         s.axes[1] = typical_axis();
         s.axes[1].slave_of = 2;
       },
       "axis.y.slave_of"},
      {"slave of an axis without sensor",
       [](Settings& s) {
         s.axes[0].mode = HomingMode::manual;
         s.axes[1] = typical_axis();
         s.axes[1].slave_of = 1;
       },
       "axis.y.slave_of"},
  };
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.what) {
      Rig r;
      c.spoil(r.settings);
      r.step();
      r.clear_trace();
      r.pending.home_all = true;
      r.step();
      r.run_for(0.5);
      CHECK(r.status().last_command_result == CommandResult::refused_settings_fault);
      CHECK_FALSE(r.status().homing);
      for (std::size_t a = 0; a < kAxisCount; ++a) CHECK(r.trace[a].path_mm == 0);
      const std::size_t axis = std::string(c.name).find("axis.y") == 0 ? 1 : 0;
      const Alarm al = r.axis(axis).alarm;
      CHECK(al.code == AlarmCode::settings_fault);
      const std::string text = describe_alarm(axis, al, r.settings);
      INFO(text);
      CHECK(text.find(c.name) != std::string::npos);
      CHECK(text.find("refused before any motion") != std::string::npos);
    }
  }
}

SCENARIO("every phase is bounded in distance", "[phases][bounds]") {
  GIVEN("no sensor at all") {
    Rig r;
    r.settings.axes[0].max_seek_travel_mm = 50;
    r.machine.axes[0].sensor_max_mm = -2000;  // max < min: no cam
    r.clear_trace();
    r.home_all(10);
    THEN("seek ends at max seek travel with sensor_not_found") {
      CHECK(r.axis(0).alarm.code == AlarmCode::sensor_not_found);
      CHECK(r.axis(0).alarm.phase == Phase::seek);
      CHECK(r.trace[0].path_mm <= 50 + 1e-9);
      CHECK(r.trace[0].path_mm == Approx(50));
    }
  }
  GIVEN("a sensor that never releases") {
    Rig r;
    r.machine.axes[0].fault = sim::Fault::sensor_stuck_active;
    r.clear_trace();
    r.home_all(30);
    THEN("back-off ends at max back-off with not_released") {
      CHECK(r.axis(0).alarm.code == AlarmCode::not_released);
      CHECK(r.axis(0).alarm.phase == Phase::back_off);
      CHECK(r.trace[0].path_mm <= r.settings.axes[0].max_backoff_mm + 1e-9);
    }
  }
  GIVEN("a sensor that does not come back on re-approach") {
    Rig r;
    r.settings.axes[0].mode = HomingMode::switch_reapproach;
    double reapproach_start = 0;
    r.on_period = [&](Rig& rr) {
      if (rr.axis(0).phase == Phase::reapproach && rr.simulator->config().axes[0].fault == sim::Fault::none) {
        auto c = rr.simulator->axis_config(0);
        c.fault = sim::Fault::sensor_stuck_inactive;
        rr.simulator->set_axis_config(0, c);
        reapproach_start = rr.simulator->actual_position_mm(0);
      }
    };
    r.home_all(30);
    THEN("re-approach ends within max back-off with reapproach_not_found") {
      CHECK(r.axis(0).alarm.code == AlarmCode::reapproach_not_found);
      CHECK(r.axis(0).alarm.phase == Phase::reapproach);
      CHECK(reapproach_start - r.actual(0) <= r.settings.axes[0].max_backoff_mm + 1e-6);
    }
  }
  GIVEN("an encoder without index pulses") {
    Rig r;
    r.settings.axes[0].mode = HomingMode::switch_index;
    r.settings.axes[0].index_pitch_mm = 5;
    r.machine.axes[0].index_pitch_mm = 0;
    double index_start = 0;
    r.on_period = [&](Rig& rr) {
      if (rr.axis(0).phase == Phase::index && index_start == 0) index_start = rr.simulator->actual_position_mm(0);
    };
    r.home_all(30);
    THEN("index ends within one pitch plus margin with index_not_found") {
      CHECK(r.axis(0).alarm.code == AlarmCode::index_not_found);
      CHECK(r.axis(0).alarm.phase == Phase::index);
      CHECK(r.actual(0) - index_start <= 5 * 1.2 + 1e-6);
    }
  }
}
