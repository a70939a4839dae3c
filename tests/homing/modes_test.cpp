// The nine homing modes: where each one puts the reference and the carriage.
#include <catch2/catch.hpp>

#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

namespace {
constexpr double kExact = 1e-9;
}

SCENARIO("disabled mode moves nothing and counts as synchronized", "[modes]") {
  GIVEN("X disabled, its carriage at 37 mm") {
    Rig r;
    r.settings.axes[0].mode = HomingMode::disabled;
    r.machine.axes[0].actual_position_mm = 37;
    r.step();
    THEN("the axis is synchronized before any homing") { CHECK(r.axis(0).homed); }
    WHEN("home-all runs") {
      r.clear_trace();
      r.home_all();
      THEN("nothing moved and the axis is homed") {
        CHECK(r.trace[0].path_mm == 0);
        CHECK(r.actual(0) == Approx(37));
        CHECK(r.axis(0).homed);
        CHECK(r.status().state == MachineState::homed);
        CHECK_FALSE(r.status().alarm);
      }
    }
  }
}

SCENARIO("manual mode assigns the home position to where the carriage stands", "[modes]") {
  Rig r;
  r.settings.axes[0].mode = HomingMode::manual;
  r.settings.axes[0].home_position_mm = 12.5;
  r.machine.axes[0].actual_position_mm = 37;
  r.step();
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK(r.trace[0].path_mm == 0);
  CHECK(r.axis(0).position_mm == Approx(12.5).margin(kExact));
  CHECK(r.axis(0).homed);
  CHECK_FALSE(r.saw(0, Phase::seek));
}

SCENARIO("switch release edge: the release is the reference, then the pull-off", "[modes]") {
  Rig r;
  r.clear_trace();
  REQUIRE(r.home_all());
  const AxisSettings& s = r.settings.axes[0];
  const double tol = edge_tolerance_mm(s, r.dt_s);
  const double release = last_release_mm(r, 0);
  CHECK(release == Approx(0.05).margin(kExact));  // cam edge + hysteresis
  CHECK(r.actual(0) == Approx(rest_point_mm(s, release)).margin(tol));
  CHECK(r.actual(0) == Approx(1.05).margin(tol));
  CHECK(r.axis(0).position_mm == Approx(0).margin(kExact));
  CHECK(r.axis(0).position_mm == Approx(true_position_mm(r, 0, rest_point_mm(s, release))).margin(tol));
  CHECK(r.saw(0, Phase::seek));
  CHECK(r.saw(0, Phase::stop));
  CHECK(r.saw(0, Phase::back_off));
  CHECK_FALSE(r.saw(0, Phase::reapproach));
  CHECK(r.saw(0, Phase::pull_off));
  CHECK(r.status().homing_cycles == 1);
}

SCENARIO("switch re-approach edge: the second trigger at latch feedrate is the reference", "[modes]") {
  Rig r;
  r.settings.axes[0].mode = HomingMode::switch_reapproach;
  r.clear_trace();
  REQUIRE(r.home_all());
  const AxisSettings& s = r.settings.axes[0];
  const double tol = edge_tolerance_mm(s, r.dt_s);
  const double trigger = last_trigger_mm(r, 0);
  CHECK(trigger == Approx(0).margin(kExact));
  CHECK(r.saw(0, Phase::reapproach));
  CHECK(r.actual(0) == Approx(rest_point_mm(s, trigger)).margin(tol));
  CHECK(r.actual(0) == Approx(1.0).margin(tol));
  CHECK(r.axis(0).position_mm == Approx(0).margin(kExact));
}

SCENARIO("switch + index: release edge, then the next index pulse is the reference", "[modes]") {
  Rig r;
  r.settings.axes[0].mode = HomingMode::switch_index;
  r.machine.axes[0].index_pitch_mm = 5;
  r.machine.axes[0].index_offset_mm = 0.3;  // pulses at ... -4.7, 0.3, 5.3 ...
  r.clear_trace();
  REQUIRE(r.home_all());
  const AxisSettings& s = r.settings.axes[0];
  const double tol = edge_tolerance_mm(s, r.dt_s);
  CHECK(r.saw(0, Phase::index));
  // Release at 0.05 while backing off toward +, the next pulse is at 0.3.
  CHECK(r.actual(0) == Approx(rest_point_mm(s, 0.3)).margin(tol));
  CHECK(r.axis(0).position_mm == Approx(0).margin(kExact));
}

SCENARIO("absolute mode takes the encoder position minus the offset without moving", "[modes]") {
  Rig r;
  r.settings.axes[0].mode = HomingMode::absolute;
  r.settings.axes[0].home_position_mm = 2;   // the offset
  r.machine.axes[0].absolute_offset_mm = 7;  // encoder reads carriage + 7
  r.machine.axes[0].actual_position_mm = 40;
  r.step();
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK(r.trace[0].path_mm == 0);
  CHECK(r.axis(0).position_mm == Approx(40 + 7 - 2).margin(kExact));
}

SCENARIO("absolute with final position moves to the final position after assigning", "[modes]") {
  Rig r;
  r.settings.axes[0].mode = HomingMode::absolute_final;
  r.settings.axes[0].home_position_mm = 2;
  r.settings.axes[0].final_position_mm = 20;
  r.machine.axes[0].absolute_offset_mm = 7;
  r.machine.axes[0].actual_position_mm = 40;
  r.step();
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK(r.saw(0, Phase::final_move));
  CHECK_FALSE(r.saw(0, Phase::seek));
  CHECK(r.axis(0).position_mm == Approx(20).margin(1e-9));
  CHECK(r.actual(0) == Approx(20 - 5).margin(1e-9));  // machine = carriage + 5
}

SCENARIO("pushing modes push into the mechanical stop with the push output on, then find the edge",
         "[modes]") {
  for (HomingMode mode : {HomingMode::pushing_release, HomingMode::pushing_reapproach}) {
    DYNAMIC_SECTION("mode " << mode_name(mode)) {
      Rig r;
      r.settings.axes[0].mode = mode;
      r.settings.axes[0].push_distance_mm = 2;
      r.machine.axes[0].hard_stop_min_mm = -1;  // the stop is 0.6 mm beyond the halt point
      bool push_output_seen = false, pushed_at_stop = false;
      r.on_period = [&](const Rig& rr) {
        if (rr.engine.outputs().axes[0].push_output) {
          push_output_seen = true;
          CHECK(rr.axis(0).phase == Phase::push);
        }
        if (rr.axis(0).phase == Phase::push && rr.simulator->at_hard_stop(0)) pushed_at_stop = true;
      };
      r.clear_trace();
      REQUIRE(r.home_all());
      CHECK(push_output_seen);
      CHECK(pushed_at_stop);
      CHECK_FALSE(r.engine.outputs().axes[0].push_output);
      CHECK(r.trace[0].min_actual == Approx(-1));  // held by the stop, never past it
      const AxisSettings& s = r.settings.axes[0];
      const double tol = edge_tolerance_mm(s, r.dt_s);
      const double edge = mode == HomingMode::pushing_release ? last_release_mm(r, 0) : last_trigger_mm(r, 0);
      CHECK(r.actual(0) == Approx(rest_point_mm(s, edge)).margin(tol));
      CHECK(r.axis(0).position_mm == Approx(0).margin(kExact));
      CHECK(r.saw(0, Phase::push));
      CHECK(r.saw(0, Phase::reapproach) == (mode == HomingMode::pushing_reapproach));
    }
  }
}

SCENARIO("a push cut short by an alarm keeps the current reduced until the axis rests", "[modes][push][alarm]") {
  // Campaign seed 35012: a communication loss stopped a push whose carriage
  // had reached the stop; the push output went off at once, and the motor
  // braked on into the stop at full current.
  Rig r;
  r.settings.axes[0].mode = HomingMode::pushing_release;
  r.settings.axes[0].push_distance_mm = 2;
  r.settings.axes[0].acceleration_mm_per_s2 = 100;  // a stop of 5 ms from latch speed
  r.machine.axes[0].hard_stop_min_mm = -1;
  r.clear_trace();
  r.pending.home_all = true;
  r.step();
  // Pushing at latch speed with the carriage held by the stop.
  REQUIRE(r.run_until([&] {
    return r.axis(0).phase == Phase::push && r.simulator->at_hard_stop(0) && r.axis(0).velocity_mm_per_s != 0;
  }, 60));
  r.pending.abort = true;
  r.step();
  REQUIRE(r.axis(0).alarm.code == AlarmCode::aborted);
  REQUIRE(r.axis(0).phase == Phase::stopping);
  int braking_periods = 0;
  while (r.axis(0).velocity_mm_per_s != 0 && braking_periods < 1000) {
    CHECK(r.engine.outputs().axes[0].push_output);
    r.step();
    ++braking_periods;
  }
  CHECK(braking_periods > 0);
  CHECK(r.axis(0).phase == Phase::idle);
  r.step();
  CHECK_FALSE(r.engine.outputs().axes[0].push_output);
  CHECK(r.trace[0].min_actual >= -1);
}

SCENARIO("final move after a switch homing when final_move_enable is set", "[modes]") {
  Rig r;
  r.settings.axes[0].final_move_enable = true;
  r.settings.axes[0].final_position_mm = 30;
  REQUIRE(r.home_all());
  CHECK(r.saw(0, Phase::final_move));
  CHECK(r.axis(0).position_mm == Approx(30).margin(1e-9));
  CHECK(r.actual(0) == Approx(31.05).margin(1e-4));
}

SCENARIO("positive direction homes onto a cam at the positive end", "[modes]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.direction = Direction::positive;
  s.home_position_mm = 250;
  r.machine.axes[0].sensor_min_mm = 300;
  r.machine.axes[0].sensor_max_mm = 2000;
  r.machine.axes[0].hard_stop_max_mm = 2100;
  REQUIRE(r.home_all());
  const double release = last_release_mm(r, 0);
  CHECK(release == Approx(299.95).margin(1e-9));
  CHECK(r.actual(0) == Approx(298.95).margin(1e-4));
  CHECK(r.axis(0).position_mm == Approx(250).margin(1e-9));
}
