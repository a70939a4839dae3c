// Drive-performed homing (axis.<a>.mode = drive): the drive homes itself on
// its own sensor while the module's home request is on; the module sends no
// steps meanwhile and assigns home_position where the drive reports done.
#include <catch2/catch.hpp>

#include "rig.hpp"

using namespace rig;

namespace {

// X homed by its drive: the drive's own home at 0, the carriage at 100.
Rig drive_rig() {
  Rig r;
  r.settings.axes[0].mode = HomingMode::drive;
  r.settings.axes[0].home_position_mm = 3;
  return r;
}

void set_fault(Rig& r, std::size_t a, sim::Fault f) {
  auto c = r.sim().axis_config(a);
  c.fault = f;
  r.sim().set_axis_config(a, c);
}

}  // namespace

SCENARIO("drive mode: the drive homes itself while the request is on, and the module sends no steps", "[drive]") {
  Rig r = drive_rig();
  r.step();
  const double motor_before = r.engine.outputs().axes[0].motor.position_mm;
  bool request_seen = false, steps_sent = false, request_outside_phase = false;
  double done_at_request = -1;
  r.on_period = [&](Rig& rig) {
    const AxisOutputs& out = rig.engine.outputs().axes[0];
    const bool homing_phase = rig.axis(0).phase == Phase::drive_homing;
    request_seen = request_seen || out.drive_request;
    if (out.drive_request != homing_phase) request_outside_phase = true;
    if (homing_phase && (out.motor.position_mm != motor_before || out.motion.target_velocity_mm_per_s != 0))
      steps_sent = true;
    if (out.drive_request && done_at_request < 0) done_at_request = rig.sim().drive_done(0) ? 1 : 0;
  };
  REQUIRE(r.home_all());
  r.on_period = nullptr;
  CHECK(request_seen);
  CHECK_FALSE(request_outside_phase);
  CHECK_FALSE(steps_sent);
  CHECK(done_at_request == 0);
  // The carriage stands at the drive's own home, and that is home_position.
  CHECK(r.actual(0) == Approx(0).margin(1e-9));
  CHECK(r.axis(0).position_mm == Approx(3).margin(1e-9));
  CHECK_FALSE(r.engine.outputs().axes[0].drive_request);
  CHECK(r.sim().drive_done(0));
  WHEN("the axis then moves") {
    r.move(0, 13);
    r.run_until([&] { return !r.any_moving() && r.axis(0).phase != Phase::move; }, 10);
    THEN("it moves in the coordinate the drive's reference gave it") {
      CHECK(r.axis(0).position_mm == Approx(13).margin(1e-6));
      CHECK(r.actual(0) == Approx(10).margin(1e-6));
    }
  }
}

SCENARIO("drive mode: the final move follows the drive's homing when enabled", "[drive]") {
  Rig r = drive_rig();
  r.settings.axes[0].final_move_enable = true;
  r.settings.axes[0].final_position_mm = 20;
  r.step();
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK(r.saw(0, Phase::drive_homing));
  CHECK(r.saw(0, Phase::final_move));
  CHECK(r.axis(0).position_mm == Approx(20).margin(1e-6));
  CHECK(r.actual(0) == Approx(17).margin(1e-6));
}

SCENARIO("drive mode: a drive that answers late, within the time limit, homes the axis", "[drive]") {
  Rig r = drive_rig();
  r.machine.axes[0].drive_answer_ms = 5000;
  r.settings.axes[0].drive_home_timeout_s = 16;  // 10 s of travel + 5 s answer
  r.step();
  CHECK(r.home_all(60));
  CHECK(r.axis(0).position_mm == Approx(3).margin(1e-9));
}

SCENARIO("drive mode: re-homing a homed axis waits for the drive to drop done and raise it again", "[drive]") {
  Rig r = drive_rig();
  r.step();
  REQUIRE(r.home_all());
  r.move(0, 53);
  r.run_until([&] { return !r.any_moving() && r.axis(0).phase != Phase::move; }, 10);
  REQUIRE(r.actual(0) == Approx(50).margin(1e-6));
  CHECK(r.home_all());
  CHECK(r.actual(0) == Approx(0).margin(1e-9));
  CHECK(r.axis(0).position_mm == Approx(3).margin(1e-9));
}

SCENARIO("drive mode: abort drops the home request and the drive stops its homing", "[drive]") {
  Rig r = drive_rig();
  r.step();
  r.pending.home_all = true;
  r.step();
  r.run_for(2);
  REQUIRE(r.axis(0).phase == Phase::drive_homing);
  REQUIRE(r.sim().drive_homing(0));
  r.pending.abort = true;
  r.step();
  CHECK_FALSE(r.engine.outputs().axes[0].drive_request);
  r.step();
  CHECK_FALSE(r.sim().drive_homing(0));
  const double x = r.actual(0);
  r.run_for(1);
  CHECK(r.actual(0) == x);
  CHECK(r.axis(0).alarm.code == AlarmCode::aborted);
  CHECK(r.axis(0).alarm.phase == Phase::drive_homing);
  CHECK_FALSE(r.axis(0).homed);
}

SCENARIO("drive mode: a drive fault while the drive homes is a drive_fault in the drive_homing phase", "[drive]") {
  Rig r = drive_rig();
  r.step();
  r.pending.home_all = true;
  r.step();
  r.run_for(1);
  REQUIRE(r.axis(0).phase == Phase::drive_homing);
  set_fault(r, 0, sim::Fault::drive_fault);
  r.step();
  r.step();
  CHECK(r.axis(0).alarm.code == AlarmCode::drive_fault);
  CHECK(r.axis(0).alarm.phase == Phase::drive_homing);
  CHECK_FALSE(r.engine.outputs().axes[0].drive_request);
  CHECK_FALSE(r.axis(0).homed);
}

SCENARIO("drive mode: the rule set wants a time limit and keeps the mode out of gantries", "[drive][settings]") {
  Settings s;
  s.axes[0] = typical_axis();
  s.axes[0].mode = HomingMode::drive;
  CHECK_FALSE(check_axis(s, 0));
  s.axes[0].drive_home_timeout_s = 0;
  const auto f = check_axis(s, 0);
  REQUIRE(f);
  CHECK(f->rule == CheckRule::missing_time_limit);
  CHECK(f->field == AxisField::drive_home_timeout);
  CHECK(describe_fault(*f, s).find("axis.x.drive_home_timeout_s is 0 s") == 0);
  s.axes[0].drive_home_timeout_s = 30;
  // A drive axis as a gantry slave, then as a master.
  s.axes[1] = typical_axis();
  s.axes[1].mode = HomingMode::drive;
  s.axes[1].slave_of = 1;
  s.axes[1].max_misalignment_mm = 2;
  s.axes[0].mode = HomingMode::switch_release;
  const auto as_slave = check_axis(s, 1);
  REQUIRE(as_slave);
  CHECK(as_slave->rule == CheckRule::slave_needs_sensor);
  s.axes[1].mode = HomingMode::switch_release;
  s.axes[0].mode = HomingMode::drive;
  const auto as_master = check_axis(s, 1);
  REQUIRE(as_master);
  CHECK(as_master->rule == CheckRule::slave_invalid);
}

SCENARIO("drive mode: an alarm raised as its step begins leaves the home request off", "[drive]") {
  // X (absolute, invalid encoder) and Y (drive) begin together: X's
  // encoder_fault stops the cycle as Y's step begins.
  Rig r;
  r.settings.axes[0].mode = HomingMode::absolute;
  r.add_axis(1, 1);
  r.settings.axes[1].mode = HomingMode::drive;
  r.tweak_inputs = [](Inputs& in) { in.axes[0].absolute_valid = false; };
  r.step();
  const double y = r.actual(1);
  bool requested = false;
  r.on_period = [&](Rig& rig) { requested = requested || rig.engine.outputs().axes[1].drive_request; };
  r.pending.home_all = true;
  r.step();
  r.run_for(1);
  r.on_period = nullptr;
  CHECK(r.axis(0).alarm.code == AlarmCode::encoder_fault);
  CHECK_FALSE(requested);
  CHECK(r.actual(1) == y);
  CHECK_FALSE(r.axis(1).homed);
}
