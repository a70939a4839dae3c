// The commissioning measurement (homing/measure.hpp): cmd.measure homes one
// axis, travels at latch feedrate to the opposite end of its travel and
// publishes the usable travel and the settings that fit it, without writing
// any setting.
#include <catch2/catch.hpp>

#include <cmath>

#include "rig.hpp"

using namespace rig;

namespace {
constexpr std::size_t X = 0;

// X homes negative on its switch (cam [-1000, 0]) between limit switches at
// -3 mm and 150 mm, its stops at -5 and 155; it starts at 100 mm.
Rig limit_switch_axis() {
  Rig r;
  r.settings.axes[X].limits_fitted = true;
  r.settings.axes[X].limit_overtravel_mm = 2;  // the stops lie 2 and 5 mm beyond the switches
  r.machine.axes[X].limit_min_mm = -3;
  r.machine.axes[X].limit_max_mm = 150;
  r.machine.axes[X].hard_stop_min_mm = -5;
  r.machine.axes[X].hard_stop_max_mm = 155;
  return r;
}

// X homes negative against its stop at -5 mm; the opposite stop is at 145 mm
// and no limit switch is fitted: only the stall input tells the far end.
Rig hard_stop_axis() {
  Rig r;
  AxisSettings& s = r.settings.axes[X];
  s.mode = HomingMode::hard_stop;
  s.stall_timeout_ms = 20'000;  // shorter than the measurement's travel: only the homing push is timed
  r.machine.axes[X].actual_position_mm = 3;
  r.machine.axes[X].hard_stop_min_mm = -5;
  r.machine.axes[X].hard_stop_max_mm = 145;
  r.machine.axes[X].sensor_min_mm = 1;  // no switch in the way
  r.machine.axes[X].sensor_max_mm = 0;
  return r;
}

// Sends cmd.measure for these axes; the command's result, then runs to the end.
CommandResult measure(Rig& r, AxisMask axes, double max_s = 400) {
  r.pending.measure_axes = axes;
  r.step();
  const CommandResult result = r.status().last_command_result;
  r.run_until([&] { return !r.status().homing; }, max_s);
  r.run_until([&] { return !r.any_moving(); }, 5);
  return result;
}

double jog_stop_mm(const AxisSettings& s) {
  const double v = s.jog_feedrate_mm_per_min / 60.0;
  return v * v / (2 * s.acceleration_mm_per_s2);
}

}  // namespace

SCENARIO("measurement of a 150 mm axis between limit switches: the usable travel within 0.01 mm of the truth, the carriage stopped just off the far switch, still homed",
         "[measure]") {
  Rig r = limit_switch_axis();
  r.clear_trace();
  REQUIRE(measure(r, axis_bit(X)) == CommandResult::accepted);
  const AxisStatus& x = r.axis(X);
  REQUIRE(x.alarm.code == AlarmCode::none);
  CHECK(r.saw(X, Phase::measure_travel));
  CHECK(x.homed);
  CHECK(x.phase == Phase::done);
  // The far switch trips at 150 mm of carriage: in machine coordinates that
  // lies where the carriage's offset puts it (no steps were lost).
  const double offset = x.position_mm - r.actual(X);
  const double truth = 150 + offset - r.settings.axes[X].home_position_mm;
  const AxisSettings& s = r.settings.axes[X];
  CHECK(x.measurement.usable_travel_mm == Approx(truth - jog_stop_mm(s)).margin(0.01));
  CHECK(x.measurement.soft_limit_min_mm == Approx(s.home_position_mm));
  CHECK(x.measurement.soft_limit_max_mm == Approx(s.home_position_mm + x.measurement.usable_travel_mm));
  // The longest seek runs from the far switch to the home switch (150 mm) plus max_stop_distance.
  CHECK(x.measurement.max_seek_travel_mm >= 150 + s.max_stop_distance_mm);
  CHECK(x.measurement.max_seek_travel_mm <= std::ceil((150.1 + s.max_stop_distance_mm) * 1.1));
  CHECK(x.measurement.max_seek_travel_mm == std::floor(x.measurement.max_seek_travel_mm));
  // Stopped just released: off the switch, by less than a tenth of a mm.
  CHECK(r.actual(X) < 150);
  CHECK(r.actual(X) > 149.9);
  CHECK(r.trace[X].max_actual < 150.1);  // braked at latch feedrate right at the switch
  CHECK_FALSE(r.status().alarm);
  // Nothing was written: the settings are those it ran with.
  CHECK(s.soft_limit_max_mm == 500);
  CHECK(s.max_seek_travel_mm == 300);

  WHEN("the axis is homed again by cmd.home") {
    r.clear_trace();
    REQUIRE(r.home_axes(axis_bit(X)));
    THEN("the home is a plain one: no measurement travel, the figures kept") {
      CHECK_FALSE(r.saw(X, Phase::measure_travel));
      CHECK(r.axis(X).measurement.usable_travel_mm == Approx(x.measurement.usable_travel_mm));
    }
  }
}

SCENARIO("measurement of a hard-stop axis: pushes into the far stop at reduced current until the stall, reports the travel, and leaves the axis to be homed again",
         "[measure]") {
  Rig r = hard_stop_axis();
  bool pushed_in_measure = false;
  r.on_period = [&](Rig& rig) {
    if (rig.axis(X).phase == Phase::measure_travel && rig.engine.outputs().axes[X].push_output) pushed_in_measure = true;
  };
  r.clear_trace();
  REQUIRE(measure(r, axis_bit(X)) == CommandResult::accepted);
  const AxisStatus& x = r.axis(X);
  REQUIRE(x.alarm.code == AlarmCode::none);
  CHECK(r.saw(X, Phase::measure_travel));
  CHECK(pushed_in_measure);
  CHECK_FALSE(r.engine.outputs().axes[X].push_output);
  // Homed pull_off (1 mm) above the stop at -5 as 0: the far stop at 145 is 149 in machine coordinates.
  const AxisSettings& s = r.settings.axes[X];
  CHECK(x.measurement.usable_travel_mm == Approx(149 - jog_stop_mm(s)).margin(0.1));
  CHECK(x.measurement.soft_limit_min_mm == Approx(0));
  CHECK(x.measurement.soft_limit_max_mm == Approx(x.measurement.usable_travel_mm));
  CHECK(r.trace[X].max_actual == Approx(145).margin(1e-9));  // reached the stop, never passed it
  CHECK(r.actual(X) == Approx(144).margin(0.01));             // pull_off below it
  // Its motor may have lost steps against the stop: no longer homed.
  CHECK_FALSE(x.homed);
  CHECK(x.phase == Phase::idle);
  CHECK_FALSE(r.status().alarm);
}

SCENARIO("measurement with no end of travel within max_seek_travel of the home raises travel_end_not_found",
         "[measure][alarms]") {
  Rig r = limit_switch_axis();
  r.machine.axes[X].limit_max_mm = 1e9;  // the far limit switch is dead
  r.machine.axes[X].hard_stop_max_mm = 1e9;
  r.settings.axes[X].max_seek_travel_mm = 50;
  r.machine.axes[X].actual_position_mm = 20;  // the home seek fits within it
  REQUIRE(measure(r, axis_bit(X)) == CommandResult::accepted);
  const AxisStatus& x = r.axis(X);
  CHECK(x.alarm.code == AlarmCode::travel_end_not_found);
  CHECK(x.alarm.phase == Phase::measure_travel);
  CHECK(x.alarm.value == Approx(50).margin(1e-6));  // bounded: it went max_seek_travel and no further
  CHECK(r.actual(X) < 1.05 + 50 + 0.01);           // from its home rest (1 mm pull-off, 0.05 hysteresis)
  CHECK(x.measurement.usable_travel_mm == 0);        // no figure from a measurement that found no end
  CHECK(describe_alarm(X, x.alarm, r.settings).find("no end of travel within 50.000 mm") != std::string::npos);
}

SCENARIO("measurement is refused, moving nothing, for axes it cannot measure", "[measure]") {
  auto refused = [](Rig& r, AxisMask axes) {
    r.step();
    const double start = r.actual(X);
    const CommandResult result = measure(r, axes, 1);
    CHECK_FALSE(r.status().homing);
    CHECK(r.actual(X) == start);
    CHECK_FALSE(r.saw(X, Phase::measure_travel));
    return result;
  };
  GIVEN("a switch axis without limit switches") {
    Rig r;
    CHECK(refused(r, axis_bit(X)) == CommandResult::refused_no_travel_end);
  }
  GIVEN("a hard-stop axis that tells its stop by following error, without limit switches") {
    Rig r = hard_stop_axis();
    r.settings.axes[X].stall_detect = StallDetect::following_error;
    CHECK(refused(r, axis_bit(X)) == CommandResult::refused_no_travel_end);
  }
  GIVEN("a home cam in mid-travel, even with limit switches") {
    Rig r = limit_switch_axis();
    r.settings.axes[X].mode = HomingMode::home_cam;
    CHECK(refused(r, axis_bit(X)) == CommandResult::refused_no_travel_end);
  }
  GIVEN("a disabled axis") {
    Rig r = limit_switch_axis();
    r.settings.axes[X].mode = HomingMode::disabled;
    CHECK(refused(r, axis_bit(X)) == CommandResult::refused_invalid);
  }
  GIVEN("one side of a gantry pair") {
    Rig r = limit_switch_axis();
    r.settings.axes[1] = r.settings.axes[X];
    r.settings.axes[1].slave_of = 1;
    r.settings.axes[1].slave_mode = SlaveMode::own_output;
    CHECK(refused(r, axis_bit(X)) == CommandResult::refused_gantry_pair);
  }
  GIVEN("a machine that homes all axes or none") {
    Rig r = limit_switch_axis();
    r.settings.global.single_axis_homing = false;
    CHECK(refused(r, axis_bit(X)) == CommandResult::refused_home_all_only);
  }
  GIVEN("two axes at once") {
    Rig r = limit_switch_axis();
    r.add_axis(1, 1);
    CHECK(refused(r, axis_bit(X) | axis_bit(1)) == CommandResult::refused_invalid);
  }
}

SCENARIO("an abort during the measurement's travel stops the axis where it is with aborted, and no figures are published",
         "[measure]") {
  Rig r = limit_switch_axis();
  r.pending.measure_axes = axis_bit(X);
  r.step();
  REQUIRE(r.status().last_command_result == CommandResult::accepted);
  REQUIRE(r.run_until([&] { return r.axis(X).phase == Phase::measure_travel && r.actual(X) > 50; }, 300));
  r.pending.abort = true;
  r.step();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(r.axis(X).alarm.code == AlarmCode::aborted);
  CHECK(r.axis(X).alarm.phase == Phase::measure_travel);
  CHECK_FALSE(r.status().homing);
  CHECK(r.actual(X) < 52);  // braked from latch feedrate
  CHECK(r.axis(X).measurement.usable_travel_mm == 0);
  r.reset_alarm();
  WHEN("the axis is then homed by cmd.home") {
    r.clear_trace();
    REQUIRE(r.home_axes(axis_bit(X)));
    THEN("no measurement travel follows") { CHECK_FALSE(r.saw(X, Phase::measure_travel)); }
  }
}

SCENARIO("a far limit switch that stays active after the measurement backs off max_backoff raises not_released naming the limit switch",
         "[measure][alarms]") {
  Rig r = limit_switch_axis();
  bool stuck = false;
  r.tweak_inputs = [&](Inputs& in) {
    if (stuck) in.axes[X].limit_max_level = true;  // a switch stuck on once met
  };
  r.on_period = [&](Rig& rig) {
    if (rig.actual(X) >= 150) stuck = true;
  };
  REQUIRE(measure(r, axis_bit(X)) == CommandResult::accepted);
  const AxisStatus& x = r.axis(X);
  CHECK(x.alarm.code == AlarmCode::not_released);
  CHECK(x.alarm.phase == Phase::measure_travel);
  CHECK(x.alarm.value == Approx(r.settings.axes[X].max_backoff_mm).margin(0.01));
  CHECK(r.actual(X) == Approx(150 - r.settings.axes[X].max_backoff_mm).margin(0.01));
  CHECK(describe_alarm(X, x.alarm, r.settings).find("far limit switch the measurement found still active") !=
        std::string::npos);
}

SCENARIO("measurement of a hard-stop axis with a pre-move: it ends far enough off the far stop for the home cycle's pre-move",
         "[measure]") {
  // Campaign seed 187000060: the measurement left the axis pull_off (1 mm)
  // off the far stop, and the home cycle the docs then ask for pre-moved
  // 3 mm away from home, into that stop at seek feedrate and full current.
  Rig r = hard_stop_axis();
  AxisSettings& s = r.settings.axes[X];
  s.pre_move_mode = PreMove::always;
  s.pre_move_distance_mm = 3;
  s.max_seek_travel_mm = 300;  // the seek from the far end: 150 mm to the home stop,
  s.stall_timeout_ms = 200'000;  // at latch feedrate (1 mm/s)
  REQUIRE(measure(r, axis_bit(X)) == CommandResult::accepted);
  REQUIRE_FALSE(r.status().alarm);
  CHECK(r.actual(X) == Approx(145 - 1 - 3).margin(0.01));  // pull_off and the pre-move below the stop
  r.clear_trace();
  CHECK(r.home_all(250));
  CHECK(r.trace[X].max_actual < 145);  // the pre-move stopped short of the far stop
  CHECK(r.axis(X).homed);
}
