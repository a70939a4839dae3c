// Every alarm code from its own fault: code, phase and text; latched until
// reset; all motion stopped while latched.
#include <catch2/catch.hpp>

#include <fmt/format.h>

#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

namespace {

// The alarm stays latched, nothing moves, homing is refused; reset clears it.
void check_latched_until_reset(Rig& r, std::size_t axis, AlarmCode code) {
  r.run_until([&] { return !r.any_moving(); }, 5);
  REQUIRE_FALSE(r.any_moving());
  const double x = r.actual(axis);
  r.clear_trace();
  r.run_for(0.3);
  for (std::size_t a = 0; a < kAxisCount; ++a) CHECK(r.trace[a].path_mm == 0);
  CHECK(r.axis(axis).alarm.code == code);
  CHECK(r.status().alarm);
  CHECK(r.status().state == MachineState::alarm);
  CHECK((r.status().interlocks & interlock::alarm_latched) != 0);
  CHECK_FALSE(r.engine.outputs().homing_done_lamp);
  r.pending.home_all = true;
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_alarm);
  r.jog(axis, +1);
  r.run_for(0.1);
  r.release_jogs();
  CHECK(r.actual(axis) == x);
  r.reset_alarm();
  CHECK(r.status().last_command_result == CommandResult::accepted);
  CHECK(r.axis(axis).alarm.code == AlarmCode::none);
  CHECK_FALSE(r.status().alarm);
}

std::string text_of(Rig& r, std::size_t axis) { return describe_alarm(axis, r.axis(axis).alarm, r.settings); }

// Runs home-all into the period that raises an alarm.
void home_into_alarm(Rig& r, double max_s = 60) {
  r.pending.home_all = true;
  r.step();
  r.run_until([&] { return r.status().alarm || !r.status().homing; }, max_s);
}

}  // namespace

SCENARIO("sensor_not_found: a wire break on a normally open sensor", "[alarms]") {
  Rig r;
  r.settings.axes[0].max_seek_travel_mm = 200;
  r.machine.axes[0].fault = sim::Fault::wire_break;
  home_into_alarm(r);
  CHECK(r.axis(0).alarm.code == AlarmCode::sensor_not_found);
  CHECK(r.axis(0).alarm.phase == Phase::seek);
  CHECK(text_of(r, 0).find("X: home sensor not found within 200 mm of travel") == 0);
  check_latched_until_reset(r, 0, AlarmCode::sensor_not_found);
}

SCENARIO("sensor_not_found: a sensor stuck inactive", "[alarms]") {
  Rig r;
  r.settings.axes[0].max_seek_travel_mm = 120;
  r.machine.axes[0].fault = sim::Fault::sensor_stuck_inactive;
  r.clear_trace();
  home_into_alarm(r);
  CHECK(r.axis(0).alarm.code == AlarmCode::sensor_not_found);
  CHECK(r.trace[0].path_mm <= 120 + 1e-9);
  // The carriage passed through the cam at 0 and went on: only the seek bound stopped it.
  CHECK(r.trace[0].min_actual == Approx(-5));  // held at the mechanical stop
}

SCENARIO("overrun_during_stop: a trigger cam shorter than the stop distance", "[alarms]") {
  Rig r;
  r.machine.axes[0].sensor_min_mm = -0.2;  // 0.2 mm cam + 0.05 hysteresis < 0.4 mm stop
  home_into_alarm(r);
  CHECK(r.axis(0).alarm.code == AlarmCode::overrun_during_stop);
  CHECK(r.axis(0).alarm.phase == Phase::stop);
  CHECK(text_of(r, 0).find("shorter than the stop distance") != std::string::npos);
  // The value: seen released about the cam and its hysteresis past the trigger.
  CHECK(r.axis(0).alarm.value > 0.2);
  CHECK(r.axis(0).alarm.value < 0.4);
  CHECK(text_of(r, 0).find(fmt::format("released {:.3f} mm after the trigger", r.axis(0).alarm.value)) !=
        std::string::npos);
  // Unfiltered input: the text names a bounce and debounce_ms as the other cause.
  REQUIRE(r.settings.axes[0].debounce_ms == 0);
  CHECK(text_of(r, 0).find("or the contact bounced") != std::string::npos);
  CHECK(text_of(r, 0).find("axis.x.debounce_ms is 0") != std::string::npos);
  // The advice what to set comes once, from what to check.
  const std::string text = text_of(r, 0);
  const auto first = text.find("set debounce_ms");
  REQUIRE(first != std::string::npos);
  CHECK(text.find("set debounce_ms", first + 1) == std::string::npos);
  CHECK(text.find("set axis.x.debounce_ms") == std::string::npos);
  check_latched_until_reset(r, 0, AlarmCode::overrun_during_stop);
}

SCENARIO("stop_distance_exceeded: contact bounce delays the trigger beyond max stop distance", "[alarms]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.debounce_ms = 20;          // needed: 0.4 + 20 mm/s · 20 ms = 0.8 mm
  s.max_stop_distance_mm = 0.85;
  r.machine.axes[0].bounce_ms = 20;  // bounce up to 20 ms more before the debounce starts
  home_into_alarm(r);
  CHECK(r.axis(0).alarm.code == AlarmCode::stop_distance_exceeded);
  CHECK(r.axis(0).alarm.phase == Phase::stop);
  CHECK(r.axis(0).alarm.value > 0.85);
  CHECK(text_of(r, 0).find("more than max_stop_distance 0.85 mm") != std::string::npos);
  check_latched_until_reset(r, 0, AlarmCode::stop_distance_exceeded);
}

SCENARIO("not_released: a sensor stuck active", "[alarms]") {
  Rig r;
  r.machine.axes[0].fault = sim::Fault::sensor_stuck_active;
  home_into_alarm(r);
  CHECK(r.axis(0).alarm.code == AlarmCode::not_released);
  CHECK(r.axis(0).alarm.phase == Phase::back_off);
  CHECK(text_of(r, 0).find("still active after backing off 10 mm") != std::string::npos);
  check_latched_until_reset(r, 0, AlarmCode::not_released);
}

SCENARIO("not_released: a wire break on a normally closed sensor reads active", "[alarms]") {
  Rig r;
  r.settings.axes[0].sensor_nc = true;
  r.machine.axes[0].sensor_nc = true;
  r.machine.axes[0].fault = sim::Fault::wire_break;
  r.clear_trace();
  home_into_alarm(r);
  CHECK(r.axis(0).alarm.code == AlarmCode::not_released);
  CHECK_FALSE(r.saw(0, Phase::stop));  // read as already active: straight to back-off
}

SCENARIO("index_not_found: no index pulse after the switch edge", "[alarms]") {
  Rig r;
  r.settings.axes[0].mode = HomingMode::switch_index;
  r.machine.axes[0].index_pitch_mm = 0;
  home_into_alarm(r);
  CHECK(r.axis(0).alarm.code == AlarmCode::index_not_found);
  CHECK(r.axis(0).alarm.phase == Phase::index);
  CHECK(text_of(r, 0).find("no encoder index pulse") != std::string::npos);
  check_latched_until_reset(r, 0, AlarmCode::index_not_found);
}

SCENARIO("slave_sensor_missing: a software-slaved axis without its own sensor", "[alarms][gantry]") {
  Rig r;
  r.settings.axes[1] = typical_axis();
  r.settings.axes[1].mode = HomingMode::manual;
  r.settings.axes[1].slave_of = 1;
  r.step();
  r.clear_trace();
  home_into_alarm(r, 1);
  CHECK(r.axis(1).alarm.code == AlarmCode::slave_sensor_missing);
  CHECK(r.status().last_command_result == CommandResult::refused_settings_fault);
  CHECK(r.trace[0].path_mm == 0);
  CHECK(r.trace[1].path_mm == 0);
  CHECK(text_of(r, 1).find("Y: software-slaved axis has no home sensor") == 0);
  check_latched_until_reset(r, 1, AlarmCode::slave_sensor_missing);
}

SCENARIO("misalignment: a gantry skewed beyond max misalignment", "[alarms][gantry]") {
  Rig r;
  r.settings.axes[1] = typical_axis();
  r.settings.axes[1].slave_of = 1;
  r.settings.axes[1].max_misalignment_mm = 2;
  r.machine.axes[1].actual_position_mm = 103;  // 3 mm behind the master
  home_into_alarm(r);
  CHECK(r.axis(1).alarm.code == AlarmCode::misalignment);
  CHECK(r.axis(1).alarm.phase == Phase::seek);
  CHECK(text_of(r, 1).find("more than max_misalignment 2 mm") != std::string::npos);
  // Stopped as soon as the skew passed the limit: the slave never reached its sensor.
  CHECK(r.actual(1) > 0);
  check_latched_until_reset(r, 1, AlarmCode::misalignment);
}

SCENARIO("hard_limit: the shared home sensor trips after homing", "[alarms][limits]") {
  Rig r;
  r.settings.axes[0].shared_limit = true;
  REQUIRE(r.home_all());
  CHECK(r.status().state == MachineState::homed);
  r.jog(0, -1);
  r.run_until([&] { return r.status().alarm; }, 10);
  r.release_jogs();
  CHECK(r.axis(0).alarm.code == AlarmCode::hard_limit);
  CHECK(text_of(r, 0).find("shared home/limit sensor tripped") != std::string::npos);
  CHECK_FALSE(r.axis(0).homed);  // global.alarm_clears_homed
  // Stopped within the jog's deceleration distance after the trip.
  const double v = mm_per_min_to_mm_per_s(r.settings.axes[0].jog_feedrate_mm_per_min);
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(r.actual(0) >= -stop_distance_mm(v, r.settings.axes[0].acceleration_mm_per_s2) - v * r.dt_s - 1e-9);
  r.reset_alarm();
  CHECK_FALSE(r.status().alarm);
}

SCENARIO("a slave moves within its master's soft limits: its own are not used", "[alarms][limits][gantry]") {
  // A slave is the second motor of the same axis: it inherits the master's
  // soft limits (homing/gantry.hpp), so tighter limits of its own neither stop
  // nor alarm the pair.
  Rig r;
  r.settings.axes[1] = typical_axis();
  r.settings.axes[1].slave_of = 1;
  r.settings.axes[1].max_misalignment_mm = 2;
  r.settings.axes[1].soft_limits_enable = true;
  r.settings.axes[1].soft_limit_min_mm = -1;
  r.settings.axes[1].soft_limit_max_mm = 10;
  r.settings.axes[0].soft_limits_enable = true;
  r.settings.axes[0].soft_limit_max_mm = 20;
  REQUIRE(r.home_all());
  r.jog(0, +1);
  r.run_for(3);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK_FALSE(r.status().alarm);
  CHECK(r.axis(0).position_mm == Approx(20).margin(1e-6));
  CHECK(r.axis(1).position_mm == Approx(20).margin(1e-6));
}

SCENARIO("soft_limit: jogging further out of tightened limits moves nothing and raises no alarm",
         "[alarms][limits]") {
  Rig r;
  REQUIRE(r.home_all());
  r.settings.axes[0].soft_limits_enable = true;
  r.settings.axes[0].soft_limit_min_mm = 10;
  r.settings.axes[0].soft_limit_max_mm = 100;
  r.clear_trace();
  r.jog(0, -1);
  r.run_for(0.5);
  r.release_jogs();
  CHECK(r.trace[0].path_mm == 0);
  CHECK_FALSE(r.status().alarm);
}

namespace {

// X homed, soft limits 0..300 mm: room to jog or move out before they are tightened.
void limit_x_to_0_300(Rig& r) {
  r.settings.axes[0].soft_limits_enable = true;
  r.settings.axes[0].soft_limit_min_mm = 0;
  r.settings.axes[0].soft_limit_max_mm = 300;
}

}  // namespace

SCENARIO("soft_limit: limits tightened past a jogging axis brake it to rest without an alarm, and it jogs back in",
         "[alarms][limits]") {
  // Found by a technician: soft_limit_max written below a jogging axis raised
  // soft_limit (an overrun: "check the mechanics for lost steps") and, with
  // alarm_clears_homed, unhomed every axis.
  Rig r;
  r.add_axis(1, 1);
  REQUIRE(r.home_all());
  REQUIRE(r.axis(1).homed);
  limit_x_to_0_300(r);
  r.jog(0, +1);
  r.run_until([&] { return r.axis(0).position_mm > 60; }, 20);
  REQUIRE(r.axis(0).velocity_mm_per_s > 0);
  const double at_change = r.axis(0).position_mm;
  const AxisSettings& s = r.settings.axes[0];
  const double stop = stop_distance_mm(mm_per_min_to_mm_per_s(s.jog_feedrate_mm_per_min), s.acceleration_mm_per_s2);
  r.settings.axes[0].soft_limit_max_mm = 20;
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK_FALSE(r.status().alarm);
  CHECK(r.axis(0).alarm.code == AlarmCode::none);
  CHECK(r.axis(0).homed);
  CHECK(r.axis(1).homed);
  CHECK(r.axis(0).position_mm <= at_change + stop + 0.1);  // braked from where the limit came
  // Held on, the button moves nothing further out; a new press out is refused; in runs.
  const double rest = r.axis(0).position_mm;
  r.run_for(0.5);
  CHECK(r.axis(0).position_mm == Approx(rest).margin(1e-9));
  r.release_jogs();
  r.step();
  r.jog(0, +1);
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_soft_limit);
  r.release_jogs();
  r.step();
  r.jog(0, -1);
  r.run_for(0.5);
  CHECK(r.axis(0).position_mm < rest);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK_FALSE(r.status().alarm);
}

SCENARIO("soft_limit: limits tightened past an axis moving to its target stop the move without an alarm",
         "[alarms][limits]") {
  Rig r;
  REQUIRE(r.home_all());
  limit_x_to_0_300(r);
  r.move(0, 200);
  r.run_until([&] { return r.axis(0).position_mm > 60; }, 20);
  REQUIRE(r.axis(0).phase == Phase::move);
  r.settings.axes[0].soft_limit_max_mm = 20;
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK_FALSE(r.status().alarm);
  CHECK(r.axis(0).homed);
  CHECK(r.axis(0).position_mm < 100);  // stopped, not carried on to 200
  CHECK(r.axis(0).phase == Phase::idle);
}

SCENARIO("soft_limit: a limit tightened just ahead of a jog, inside its braking distance, brakes it without an alarm",
         "[alarms][limits]") {
  Rig r;
  REQUIRE(r.home_all());
  limit_x_to_0_300(r);
  r.settings.axes[0].jog_feedrate_mm_per_min = 3000;  // 50 mm/s: a stop long enough to tighten the limit inside
  r.jog(0, +1);
  r.run_until([&] { return r.axis(0).position_mm > 60; }, 20);
  const AxisSettings& s = r.settings.axes[0];
  const double stop = stop_distance_mm(mm_per_min_to_mm_per_s(s.jog_feedrate_mm_per_min), s.acceleration_mm_per_s2);
  REQUIRE(r.axis(0).velocity_mm_per_s == Approx(50));
  REQUIRE(stop > 0.2);
  r.settings.axes[0].soft_limit_max_mm = r.axis(0).position_mm + stop / 2;  // it cannot stop before it
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK_FALSE(r.status().alarm);
  CHECK(r.axis(0).homed);
  r.release_jogs();
}

SCENARIO("soft_limit: a limit tightened ahead of a running move ends the move at the limit without an alarm",
         "[alarms][limits]") {
  Rig r;
  REQUIRE(r.home_all());
  limit_x_to_0_300(r);
  r.move(0, 200);
  r.run_until([&] { return r.axis(0).position_mm > 60; }, 20);
  r.settings.axes[0].soft_limit_max_mm = 150;  // well ahead: room to stop there
  r.run_until([&] { return !r.any_moving() && r.axis(0).phase == Phase::idle; }, 20);
  CHECK_FALSE(r.status().alarm);
  CHECK(r.axis(0).position_mm == Approx(150).margin(1e-6));
}

namespace {

// Starts home-all and runs until the seek is at full speed, far from the sensor.
void run_to_full_seek(Rig& r) {
  r.pending.home_all = true;
  r.step();
  r.run_until([&] { return r.axis(0).phase == Phase::seek && r.actual(0) < 80; }, 10);
  REQUIRE(r.axis(0).velocity_mm_per_s == Approx(-20));
}

double seek_stop_mm(const Rig& r) {
  const AxisSettings& s = r.settings.axes[0];
  return stop_distance_mm(mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min), s.acceleration_mm_per_s2);
}

}  // namespace

SCENARIO("aborted: abort during a cycle stops within the deceleration distance", "[alarms][stop]") {
  Rig r;
  run_to_full_seek(r);
  const double at_event = r.actual(0);
  r.pending.abort = true;
  r.step();
  CHECK(r.axis(0).alarm.code == AlarmCode::aborted);
  CHECK(r.axis(0).alarm.phase == Phase::seek);
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(at_event - r.actual(0) <= seek_stop_mm(r) + 1e-9);
  CHECK(at_event - r.actual(0) == Approx(seek_stop_mm(r)).margin(1e-6));
  CHECK(text_of(r, 0).find("homing aborted by command during seek") != std::string::npos);
  check_latched_until_reset(r, 0, AlarmCode::aborted);
}

namespace {

// A home-all in two steps, Z seeking in the first while X and Y wait for the second.
void start_z_first_cycle(Rig& r) {
  r.settings.global.sequence_steps = {axis_bit(2), 0, 0, 0, 0, 0};
  r.add_axis(2, 1);  // Z seeks first
  r.add_axis(0, 2);  // X waits for step 2
  r.add_axis(1, 2);  // Y too
  r.pending.home_all = true;
  r.step();
  r.run_until([&] { return r.axis(2).phase == Phase::seek; }, 5);
  REQUIRE(r.axis(0).phase == Phase::waiting);
}

}  // namespace

SCENARIO("aborted: the machine's alarm axis is the one that was moving, not one waiting for its step",
         "[alarms][stop]") {
  Rig r;  // X in step 1
  start_z_first_cycle(r);
  r.pending.abort = true;
  r.step();
  CHECK(r.axis(2).alarm.code == AlarmCode::aborted);
  CHECK(r.status().first_alarm_axis == 2);
  CHECK(reported_alarm_axis(r.status()) == 2);
}

SCENARIO("emergency_stop: the machine's alarm axis is the one that was moving, not one waiting for its step",
         "[alarms][stop]") {
  Rig r;  // X in step 1
  start_z_first_cycle(r);
  r.sim().set_estop(true);
  r.step();
  CHECK(r.axis(2).alarm.code == AlarmCode::emergency_stop);
  CHECK(r.status().first_alarm_axis == 2);
  CHECK(reported_alarm_axis(r.status()) == 2);
}

SCENARIO("emergency_stop: e-stop during a cycle stops within the deceleration distance", "[alarms][stop]") {
  Rig r;
  run_to_full_seek(r);
  const double at_event = r.actual(0);
  r.sim().set_estop(true);
  r.step();
  CHECK(r.axis(0).alarm.code == AlarmCode::emergency_stop);
  CHECK(r.status().global_alarm == AlarmCode::emergency_stop);
  CHECK((r.status().interlocks & interlock::estop) != 0);
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(at_event - r.actual(0) <= seek_stop_mm(r) + 1e-9);
  CHECK(text_of(r, 0).find("emergency stop during seek") != std::string::npos);
  THEN("reset is refused while the e-stop is pressed") {
    r.reset_alarm();
    CHECK(r.status().last_command_result == CommandResult::refused_cause_present);
    CHECK(r.status().alarm);
    r.pending.home_all = true;
    r.step();
    CHECK(r.status().last_command_result == CommandResult::refused_estop);
    r.sim().set_estop(false);
    r.step();
    check_latched_until_reset(r, 0, AlarmCode::emergency_stop);
    CHECK(r.status().global_alarm == AlarmCode::none);
  }
}

SCENARIO("emergency_stop at rest is the machine's alarm and its text names no axis", "[alarms]") {
  Rig r;
  r.sim().set_estop(true);
  r.step();
  CHECK(r.status().global_alarm == AlarmCode::emergency_stop);
  CHECK_FALSE(r.axis(0).alarm);
  const std::string text = describe_global_alarm(AlarmCode::emergency_stop, r.settings);
  CHECK(text.find("emergency stop pressed; ") == 0);
  CHECK(text.find("X:") == std::string::npos);
  CHECK(text.find(std::string(alarm_what_to_check(AlarmCode::emergency_stop))) != std::string::npos);
  // settings_lost never had an axis letter: the same text either way.
  CHECK(describe_global_alarm(AlarmCode::settings_lost, r.settings) ==
        describe_alarm(0, Alarm{AlarmCode::settings_lost}, r.settings));
}

SCENARIO("drive_fault: a faulted drive raises its alarm and motion stops", "[alarms][stop]") {
  Rig r;
  run_to_full_seek(r);
  const double at_event = r.actual(0);
  const double motor_at_event = r.engine.outputs().axes[0].motor.position_mm;
  auto c = r.sim().axis_config(0);
  c.fault = sim::Fault::drive_fault;
  r.sim().set_axis_config(0, c);
  r.step();  // the period in which the drive faulted
  r.step();  // the engine sees it
  CHECK(r.axis(0).alarm.code == AlarmCode::drive_fault);
  CHECK((r.status().interlocks & interlock::drive_fault) != 0);
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(std::abs(at_event - r.actual(0)) <= seek_stop_mm(r) + 1e-9);
  // The commanded motion too: one period before the fault was seen, then the ramp down.
  const double v = 20;
  CHECK(motor_at_event - r.engine.outputs().axes[0].motor.position_mm <= seek_stop_mm(r) + 2 * v * r.dt_s + 1e-9);
  CHECK(text_of(r, 0).find("drive fault during seek") != std::string::npos);
  r.reset_alarm();
  CHECK(r.status().last_command_result == CommandResult::refused_cause_present);
  c.fault = sim::Fault::none;
  r.sim().set_axis_config(0, c);
  r.step();
  check_latched_until_reset(r, 0, AlarmCode::drive_fault);
}

SCENARIO("communication_lost: the watchdog expires during a cycle", "[alarms][stop]") {
  Rig r;
  run_to_full_seek(r);
  const double at_event = r.actual(0);
  bool lost = true;
  r.tweak_inputs = [&](Inputs& in) { in.communication_lost = lost; };
  r.step();
  CHECK(r.axis(0).alarm.code == AlarmCode::communication_lost);
  CHECK((r.status().interlocks & interlock::communication_lost) != 0);
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(at_event - r.actual(0) <= seek_stop_mm(r) + 1e-9);
  CHECK(text_of(r, 0).find("communication lost") != std::string::npos);
  r.reset_alarm();
  CHECK(r.status().last_command_result == CommandResult::refused_cause_present);
  lost = false;
  r.step();
  check_latched_until_reset(r, 0, AlarmCode::communication_lost);
}

namespace {

// X homes in step 1, Y in step 2.
Rig two_step_rig() {
  Rig r;
  r.settings.axes[1] = typical_axis();
  r.settings.global.sequence_steps = {axis_bit(0), axis_bit(1), 0, 0, 0, 0};
  return r;
}

}  // namespace

SCENARIO("communication_lost: a cycle at rest between two moves stops too and nothing moves after",
         "[alarms][stop]") {
  // Found by the campaign (seed 908624361): the link was lost in the period a
  // pull-off came to rest, so nothing was moving when the engine read it,
  // and the cycle went on (its next move would have run one period first).
  std::uint64_t rest_period = 0;
  {
    Rig probe = two_step_rig();
    probe.pending.home_all = true;
    probe.step();
    REQUIRE(probe.run_until([&] { return probe.axis(0).phase == Phase::pull_off; }, 60));
    REQUIRE(probe.run_until([&] { return probe.axis(0).phase != Phase::pull_off; }, 10));
    rest_period = probe.periods;
  }
  Rig r = two_step_rig();
  r.pending.home_all = true;
  r.step();
  while (r.periods + 1 < rest_period) r.step();
  REQUIRE(r.axis(0).phase == Phase::pull_off);
  const double y_at_loss = r.actual(1);
  r.tweak_inputs = [](Inputs& in) { in.communication_lost = true; };
  r.step();
  CHECK(r.axis(0).velocity_mm_per_s == 0);
  CHECK(r.axis(0).alarm.code == AlarmCode::communication_lost);
  r.run_for(0.5);
  CHECK_FALSE(r.status().homing);
  CHECK(r.status().homing_cycles == 0);
  CHECK(r.actual(1) == y_at_loss);
}

SCENARIO("settings_fault: a setting that cannot work", "[alarms]") {
  Rig r;
  r.settings.axes[0].max_stop_distance_mm = 0.2;
  home_into_alarm(r, 1);
  CHECK(r.axis(0).alarm.code == AlarmCode::settings_fault);
  CHECK(r.axis(0).alarm.phase == Phase::idle);
  CHECK(text_of(r, 0).find("axis.x.max_stop_distance") != std::string::npos);
  r.settings.axes[0].max_stop_distance_mm = 10;
  check_latched_until_reset(r, 0, AlarmCode::settings_fault);
  REQUIRE(r.home_all());
}

SCENARIO("settings_lost: the settings had to be reset to defaults", "[alarms]") {
  Rig r;
  bool lost = true;
  r.tweak_inputs = [&](Inputs& in) { in.settings_lost = lost; };
  r.step();
  lost = false;
  r.step();
  CHECK(r.status().global_alarm == AlarmCode::settings_lost);
  CHECK((r.status().interlocks & interlock::settings_lost) != 0);
  CHECK(describe_alarm(0, Alarm{AlarmCode::settings_lost}, r.settings).find("settings lost") == 0);
  r.pending.home_all = true;
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_alarm);
  r.clear_trace();
  r.run_for(0.2);
  CHECK(r.trace[0].path_mm == 0);
  r.reset_alarm();
  CHECK(r.status().global_alarm == AlarmCode::none);
  REQUIRE(r.home_all());
}

SCENARIO("reapproach_not_found: the sensor does not trigger again", "[alarms]") {
  Rig r;
  r.settings.axes[0].mode = HomingMode::switch_reapproach;
  r.on_period = [&](Rig& rr) {
    if (rr.axis(0).phase == Phase::reapproach) {
      auto c = rr.simulator->axis_config(0);
      c.fault = sim::Fault::sensor_stuck_inactive;
      rr.simulator->set_axis_config(0, c);
    }
  };
  home_into_alarm(r);
  r.on_period = nullptr;
  CHECK(r.axis(0).alarm.code == AlarmCode::reapproach_not_found);
  CHECK(r.axis(0).alarm.phase == Phase::reapproach);
  CHECK(text_of(r, 0).find("not found again within 10 mm while re-approaching") != std::string::npos);
  check_latched_until_reset(r, 0, AlarmCode::reapproach_not_found);
}

SCENARIO("permit_withdrawn: the homing permit goes off during a cycle", "[alarms][permit]") {
  Rig r;
  r.settings.global.permit_required = true;
  r.sim().set_homing_permit(true);
  run_to_full_seek(r);
  const double at_event = r.actual(0);
  r.sim().set_homing_permit(false);
  r.step();
  CHECK(r.axis(0).alarm.code == AlarmCode::permit_withdrawn);
  CHECK(r.axis(0).alarm.phase == Phase::seek);
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(at_event - r.actual(0) <= seek_stop_mm(r) + 1e-9);
  CHECK(text_of(r, 0).find("homing permit went off during seek") != std::string::npos);
  check_latched_until_reset(r, 0, AlarmCode::permit_withdrawn);
}

SCENARIO("encoder_fault: absolute mode without a valid encoder position", "[alarms]") {
  Rig r;
  r.settings.axes[0].mode = HomingMode::absolute;
  r.tweak_inputs = [](Inputs& in) { in.axes[0].absolute_valid = false; };
  r.clear_trace();
  home_into_alarm(r, 1);
  CHECK(r.axis(0).alarm.code == AlarmCode::encoder_fault);
  CHECK(r.trace[0].path_mm == 0);
  CHECK(text_of(r, 0).find("absolute encoder gives no valid position") != std::string::npos);
  r.tweak_inputs = [](Inputs&) {};
  check_latched_until_reset(r, 0, AlarmCode::encoder_fault);
}

SCENARIO("unlock_not_confirmed: a locking indexer stuck locked when the axis is to home", "[alarms][indexer]") {
  Rig r;
  r.fit_indexer(0, 50, 300);
  r.machine.axes[0].fault = sim::Fault::indexer_stuck_locked;
  r.clear_trace();
  home_into_alarm(r, 2);
  CHECK(r.axis(0).alarm.code == AlarmCode::unlock_not_confirmed);
  CHECK(r.axis(0).alarm.phase == Phase::unlock);
  CHECK(r.trace[0].path_mm == 0);
  CHECK(r.sim().time_s() == Approx(0.3).margin(0.005));
  CHECK(text_of(r, 0).find("X: locking indexer not reported unlocked within lock_timeout_ms 300 ms") == 0);
  check_latched_until_reset(r, 0, AlarmCode::unlock_not_confirmed);
}

SCENARIO("lock_not_confirmed: a locking indexer that does not lock again after a move", "[alarms][indexer]") {
  Rig r;
  r.fit_indexer(0, 50, 300);
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.step();
  r.move(0, 5);
  r.run_until([&] { return r.axis(0).phase == Phase::move; }, 1);
  r.set_fault(0, sim::Fault::indexer_never_locks);
  r.run_until([&] { return r.axis(0).phase == Phase::lock; }, 5);
  REQUIRE(r.axis(0).phase == Phase::lock);
  const double rest_s = r.sim().time_s();
  r.run_until([&] { return r.status().alarm; }, 2);
  CHECK(r.axis(0).alarm.code == AlarmCode::lock_not_confirmed);
  CHECK(r.axis(0).alarm.phase == Phase::lock);
  CHECK(r.sim().time_s() - rest_s == Approx(0.3).margin(0.005));
  CHECK(r.axis(0).position_mm == Approx(5).margin(1e-9));
  CHECK(text_of(r, 0).find("X: locking indexer not reported locked within lock_timeout_ms 300 ms") == 0);
  r.set_fault(0, sim::Fault::none);
  check_latched_until_reset(r, 0, AlarmCode::lock_not_confirmed);
  r.run_for(0.2);
  CHECK(r.sim().indexer_locked(0));
  CHECK_FALSE(r.status().alarm);
}

SCENARIO("lock_engaged: a locking indexer that locks on its own under a jog", "[alarms][indexer]") {
  Rig r;
  r.fit_indexer(0, 50, 300);
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.step();
  r.jog(0, +1);
  r.run_until([&] { return r.axis(0).phase == Phase::jog && r.axis(0).velocity_mm_per_s > 0; }, 1);
  r.run_for(0.05);
  r.set_fault(0, sim::Fault::indexer_stuck_locked);
  r.step();  // the period in which the pin went in
  r.step();  // the engine sees it
  CHECK(r.axis(0).alarm.code == AlarmCode::lock_engaged);
  CHECK(r.axis(0).alarm.phase == Phase::jog);
  CHECK(r.engine.outputs().axes[0].motion.target_velocity_mm_per_s == 0);
  CHECK(text_of(r, 0).find("X: locking indexer reported locked during jog") == 0);
  r.release_jogs();
  r.set_fault(0, sim::Fault::none);
  check_latched_until_reset(r, 0, AlarmCode::lock_engaged);
}

SCENARIO("every alarm code has a name and a text", "[alarms]") {
  Settings s;
  s.axes[0] = typical_axis();
  for (std::uint8_t c = 1; c < kAlarmCodeCount; ++c) {
    const auto code = static_cast<AlarmCode>(c);
    CHECK_FALSE(alarm_name(code).empty());
    CHECK(alarm_name(code) != "?");
    CHECK(describe_alarm(0, Alarm{code, Phase::seek}, s).size() > 20);
  }
}

SCENARIO("global.alarm_clears_homed decides whether an alarm clears the homed state", "[alarms]") {
  for (bool clears : {true, false}) {
    DYNAMIC_SECTION("alarm_clears_homed = " << clears) {
      Rig r;
      r.settings.global.alarm_clears_homed = clears;
      REQUIRE(r.home_all());
      r.sim().set_estop(true);
      r.step();
      CHECK(r.status().alarm);
      CHECK(r.axis(0).homed == !clears);
      r.sim().set_estop(false);
      r.reset_alarm();
      CHECK(r.axis(0).homed == !clears);
      CHECK(r.status().state == (clears ? MachineState::not_homed : MachineState::homed));
    }
  }
}

SCENARIO("the first alarm on an axis wins, and an alarm on one axis stops every axis", "[alarms][stop]") {
  Rig r;
  r.add_axis(1, 1);  // X and Y seek together
  run_to_full_seek(r);
  REQUIRE(r.axis(1).phase == Phase::seek);
  WHEN("Y's drive faults, then the e-stop is pressed while both still brake") {
    auto c = r.sim().axis_config(1);
    c.fault = sim::Fault::drive_fault;
    r.sim().set_axis_config(1, c);
    r.step();  // the period in which the drive faulted
    r.step();  // the engine sees it
    REQUIRE(r.axis(1).alarm.code == AlarmCode::drive_fault);
    THEN("Y's alarm names the drive fault in the seek, and X brakes without an alarm of its own") {
      CHECK(r.axis(1).alarm.phase == Phase::seek);
      CHECK(r.axis(0).alarm.code == AlarmCode::none);
      CHECK(r.axis(0).phase == Phase::stopping);
      CHECK_FALSE(r.status().homing);
    }
    REQUIRE(r.any_moving());
    r.sim().set_estop(true);
    r.step();
    THEN("the e-stop latches only on X, which had no alarm yet; Y keeps its first one") {
      CHECK(r.axis(0).alarm.code == AlarmCode::emergency_stop);
      CHECK(r.axis(0).alarm.phase == Phase::stopping);
      CHECK(r.axis(1).alarm.code == AlarmCode::drive_fault);
      CHECK(r.axis(1).alarm.phase == Phase::seek);
      CHECK(r.status().global_alarm == AlarmCode::emergency_stop);
    }
    THEN("both come to rest and stay there") {
      r.run_until([&] { return !r.any_moving(); }, 5);
      REQUIRE_FALSE(r.any_moving());
      r.clear_trace();
      r.run_for(0.3);
      CHECK(r.trace[0].path_mm == 0);
      CHECK(r.trace[1].path_mm == 0);
    }
  }
}

SCENARIO("a drive that faults while its axis moves unhomes that axis even with alarm_clears_homed off",
         "[alarms][stop]") {
  Rig r;
  r.add_axis(1, 2);
  r.settings.global.alarm_clears_homed = false;
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  REQUIRE(r.home_all());
  r.held.jog[1] = 1;  // Y moves
  r.run_for(0.3);
  REQUIRE(r.axis(1).velocity_mm_per_s != 0);
  auto c = r.sim().axis_config(1);
  c.fault = sim::Fault::drive_fault;
  r.sim().set_axis_config(1, c);
  r.run_for(0.5);  // the engine brakes, the faulted drive does not follow its steps
  r.held.jog[1] = 0;
  REQUIRE(r.axis(1).alarm.code == AlarmCode::drive_fault);
  CHECK_FALSE(r.axis(1).homed);  // where it stands is no longer known
  CHECK(r.axis(0).homed);        // X did not move and keeps its coordinate
}

SCENARIO("an axis alarm clears every axis's homed state exactly when global.alarm_clears_homed is set",
         "[alarms]") {
  for (bool clears : {true, false}) {
    DYNAMIC_SECTION("alarm_clears_homed = " << clears) {
      Rig r;
      r.add_axis(1, 2);
      r.settings.global.alarm_clears_homed = clears;
      REQUIRE(r.home_all());
      REQUIRE(r.axis(0).homed);
      REQUIRE(r.axis(1).homed);
      auto c = r.sim().axis_config(1);
      c.fault = sim::Fault::drive_fault;
      r.sim().set_axis_config(1, c);
      r.step();
      r.step();
      REQUIRE(r.axis(1).alarm.code == AlarmCode::drive_fault);
      CHECK(r.status().global_alarm == AlarmCode::none);
      CHECK(r.axis(0).homed == !clears);  // the other axis too
      CHECK(r.axis(1).homed == !clears);
      c.fault = sim::Fault::none;
      r.sim().set_axis_config(1, c);
      r.step();
      r.reset_alarm();
      CHECK(r.status().last_command_result == CommandResult::accepted);
      CHECK(r.status().state == (clears ? MachineState::not_homed : MachineState::homed));
    }
  }
}

namespace {
Rig drive_axis_rig(sim::Fault fault) {
  Rig r;
  r.settings.axes[0].mode = HomingMode::drive;
  r.settings.axes[0].drive_home_timeout_s = 20;
  r.machine.axes[0].fault = fault;
  return r;
}
}  // namespace

SCENARIO("drive_no_answer: the drive begins homing on the request and never reports done", "[alarms][drive]") {
  Rig r = drive_axis_rig(sim::Fault::drive_never_answers);
  r.step();
  r.pending.home_all = true;
  r.step();
  const double requested_at = r.sim().time_s();
  r.run_until([&] { return r.status().alarm || !r.status().homing; }, 60);
  CHECK(r.axis(0).alarm.code == AlarmCode::drive_no_answer);
  CHECK(r.axis(0).alarm.phase == Phase::drive_homing);
  // Not before the time limit.
  CHECK(r.sim().time_s() - requested_at >= 20 - 0.002);
  CHECK_FALSE(r.engine.outputs().axes[0].drive_request);
  CHECK(text_of(r, 0).find("X: the drive did not report home done within 20 s of the home request") == 0);
  check_latched_until_reset(r, 0, AlarmCode::drive_no_answer);
}

SCENARIO("drive_answered_at_once: home done arrives in the first period after the request", "[alarms][drive]") {
  Rig r = drive_axis_rig(sim::Fault::drive_answers_at_once);
  r.step();
  r.clear_trace();
  home_into_alarm(r, 5);
  CHECK(r.axis(0).alarm.code == AlarmCode::drive_answered_at_once);
  CHECK(r.axis(0).alarm.phase == Phase::drive_homing);
  CHECK(r.axis(0).alarm.value < kDriveMinHomingTime_s);
  CHECK(r.trace[0].path_mm == 0);
  CHECK_FALSE(r.axis(0).homed);
  CHECK(text_of(r, 0).find("sooner than any homing") != std::string::npos);
  check_latched_until_reset(r, 0, AlarmCode::drive_answered_at_once);
}

SCENARIO("drive_answered_at_once: a drive that keeps an old home done on and never drops it", "[alarms][drive]") {
  Rig r = drive_axis_rig(sim::Fault::none);
  r.step();
  REQUIRE(r.home_all());
  REQUIRE(r.sim().drive_done(0));
  // The drive now ignores requests but keeps its old done on.
  auto c = r.sim().axis_config(0);
  c.fault = sim::Fault::drive_answers_at_once;
  r.sim().set_axis_config(0, c);
  home_into_alarm(r, 5);
  CHECK(r.axis(0).alarm.code == AlarmCode::drive_answered_at_once);
  CHECK(r.axis(0).alarm.value == Approx(kDriveMinHomingTime_s).margin(0.002));
  check_latched_until_reset(r, 0, AlarmCode::drive_answered_at_once);
}

SCENARIO("drive_reference_lost: home done goes off while the axis is homed", "[alarms][drive]") {
  for (bool clears : {true, false}) {
    DYNAMIC_SECTION("alarm_clears_homed = " << clears) {
      Rig r = drive_axis_rig(sim::Fault::none);
      r.settings.global.alarm_clears_homed = clears;
      r.step();
      REQUIRE(r.home_all());
      r.run_for(0.5);
      REQUIRE_FALSE(r.status().alarm);
      auto c = r.sim().axis_config(0);
      c.fault = sim::Fault::drive_done_lost;
      r.sim().set_axis_config(0, c);
      r.step();
      r.step();
      CHECK(r.axis(0).alarm.code == AlarmCode::drive_reference_lost);
      // Unhomed whatever alarm_clears_homed says: its coordinate rested on the drive's reference.
      CHECK_FALSE(r.axis(0).homed);
      CHECK(text_of(r, 0).find("X: the drive's home done went off at 0.000 mm while the axis was homed") == 0);
      check_latched_until_reset(r, 0, AlarmCode::drive_reference_lost);
      CHECK_FALSE(r.axis(0).homed);
      // With the drive repaired the axis homes again.
      c.fault = sim::Fault::none;
      r.sim().set_axis_config(0, c);
      CHECK(r.home_all());
    }
  }
}

SCENARIO("switch_not_repeatable: the latch passes of a noisy switch disagree beyond max_latch_spread",
         "[alarms]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.mode = HomingMode::switch_reapproach;
  s.latch_passes = 5;
  s.max_latch_spread_mm = 0.01;
  r.machine.axes[0].noise_mm = 0.05;
  r.home_all();
  CHECK(r.axis(0).alarm.code == AlarmCode::switch_not_repeatable);
  CHECK(r.axis(0).alarm.phase == Phase::reapproach);
  CHECK_FALSE(r.axis(0).homed);
  CHECK(r.axis(0).health.latch_passes == 5);
  CHECK(r.axis(0).alarm.value == r.axis(0).health.latch_spread_mm);
  CHECK(r.axis(0).alarm.value > 0.01);
  const std::string text = text_of(r, 0);
  CHECK(text.find("X: switch not repeatable: spread ") == 0);
  CHECK(text.find(" mm over 5 passes, limit 0.010 mm; check the switch's mounting, the cam, and the latch "
                  "feedrate") != std::string::npos);
  check_latched_until_reset(r, 0, AlarmCode::switch_not_repeatable);
}

SCENARIO("encoder_reversed: hard-stop homing by following error with an encoder that counts the wrong way",
         "[alarms]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.mode = HomingMode::hard_stop;
  s.stall_detect = StallDetect::following_error;
  s.max_following_error_mm = 0.4;
  r.machine.axes[0].actual_position_mm = 3;  // its stop at -5 mm
  r.machine.axes[0].sensor_min_mm = 1;
  r.machine.axes[0].sensor_max_mm = 0;
  r.machine.axes[0].fault = sim::Fault::encoder_reversed;
  r.clear_trace();
  home_into_alarm(r);
  CHECK(r.axis(0).alarm.code == AlarmCode::encoder_reversed);
  CHECK(r.axis(0).alarm.phase == Phase::push_to_stop);
  // It counted back a quarter of the limit: the carriage went as far the other way.
  CHECK(r.axis(0).alarm.value == Approx(0.1).margin(0.002));
  CHECK_FALSE(r.axis(0).homed);
  CHECK(r.trace[0].min_actual > 3 - 0.2);  // stopped long before the stop, nothing homed in free air
  CHECK(text_of(r, 0).find("X: the encoder counted 0.10") == 0);
  CHECK_THAT(text_of(r, 0), Catch::Contains("check the encoder's counting direction"));
  r.set_fault(0, sim::Fault::none);
  check_latched_until_reset(r, 0, AlarmCode::encoder_reversed);
}

SCENARIO("the axis that latched the first alarm stays the one reported when a lower axis latches one later",
         "[alarms]") {
  // Y fails first (its sensor out of its seek's reach); while it rests, X's drive faults.
  Rig r;
  r.add_axis(1, 1);
  r.settings.axes[1].max_seek_travel_mm = 50;
  r.pending.home_all = true;
  r.step();
  REQUIRE(r.run_until([&] { return bool(r.axis(1).alarm); }, 30));
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(r.status().first_alarm_axis == 1);
  r.set_fault(0, sim::Fault::drive_fault);
  r.step();
  r.step();
  REQUIRE(r.axis(0).alarm.code == AlarmCode::drive_fault);
  CHECK(r.axis(1).alarm.code == AlarmCode::sensor_not_found);
  CHECK(r.status().first_alarm_axis == 1);
  CHECK(reported_alarm_axis(r.status()) == 1);
  r.set_fault(0, sim::Fault::none);
  r.step();
  r.reset_alarm();
  CHECK(r.status().first_alarm_axis == -1);
  CHECK(reported_alarm_axis(r.status()) == -1);
}
