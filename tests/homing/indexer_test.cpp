// The locking indexer (axis.<a>.indexer_lock, docs/homing-methods.md "Locking indexer") on
// the simulator: unlocked before every motion of its axis, locked again once
// it rests, and nothing moves while it is locked. Its alarms have their own
// scenarios in alarms_test.cpp.
#include <catch2/catch.hpp>

#include "homing/settings_check.hpp"
#include "rig.hpp"

using namespace rig;

namespace {

constexpr std::size_t A = 3;  // the rotary axis the indexer is for

// A homes alone (X does not home) on a locking indexer that takes 50 ms
// each way; A starts 100 deg from its switch.
Rig indexer_rig() {
  Rig r;
  r.settings.axes[0].mode = HomingMode::disabled;
  r.settings.axes[A] = typical_axis();
  r.settings.global.sequence_steps = {axis_bit(A), 0, 0, 0, 0, 0};
  r.fit_indexer(A);
  return r;
}

// Per period: the carriage never moves, nor its motor runs, while the
// simulated pin is in; and the unlock output is on whenever the motor runs.
struct LockWatch {
  bool moved_while_locked = false;
  bool motion_without_unlock = false;
  bool saw_unlock = false, saw_lock = false;
  double locked_at_mm = 0;
  bool was_locked = false;
  void attach(Rig& r) {
    r.on_period = [this](Rig& rig) {
      sim::Simulator& s = rig.sim();
      moved_while_locked = moved_while_locked || s.moved_while_locked(A) ||
                           (was_locked && s.actual_position_mm(A) != locked_at_mm);
      const AxisOutputs& out = rig.engine.outputs().axes[A];
      if ((out.motion.target_velocity_mm_per_s != 0 || out.motor.velocity_mm_per_s != 0) && !out.indexer_unlock)
        motion_without_unlock = true;
      saw_unlock = saw_unlock || rig.axis(A).phase == Phase::unlock;
      saw_lock = saw_lock || rig.axis(A).phase == Phase::lock;
      was_locked = s.indexer_locked(A);
      locked_at_mm = s.actual_position_mm(A);
    };
  }
};

}  // namespace

SCENARIO("an indexer axis unlocks before it homes and locks again after its cycle", "[indexer]") {
  Rig r = indexer_rig();
  r.step();
  REQUIRE(r.sim().indexer_locked(A));
  LockWatch w;
  w.attach(r);
  r.pending.home_all = true;
  r.step();
  THEN("the cycle starts held in phase unlock with the unlock output on, the carriage still") {
    CHECK(r.axis(A).phase == Phase::unlock);
    CHECK(r.engine.outputs().axes[A].indexer_unlock);
    CHECK(r.engine.outputs().axes[A].motion.target_velocity_mm_per_s == 0);
    r.run_for(0.03);  // less than the 50 ms the pin needs
    CHECK(r.axis(A).phase == Phase::unlock);
    CHECK(r.actual(A) == 100);
  }
  r.run_until([&] { return !r.status().homing; }, 60);
  r.run_until([&] { return r.sim().indexer_locked(A) && r.axis(A).phase == Phase::done; }, 2);
  THEN("it homes, ends locked and showed both indexer phases; nothing moved while locked") {
    CHECK(r.axis(A).homed);
    CHECK_FALSE(r.status().alarm);
    CHECK(r.sim().indexer_locked(A));
    CHECK_FALSE(r.engine.outputs().axes[A].indexer_unlock);
    CHECK(w.saw_unlock);
    CHECK(w.saw_lock);
    CHECK_FALSE(w.moved_while_locked);
    CHECK_FALSE(w.motion_without_unlock);
    CHECK(r.status().state == MachineState::homed);
  }
}

SCENARIO("a jog on an indexer axis waits for the unlock and locks again once released", "[indexer]") {
  Rig r = indexer_rig();
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.step();
  LockWatch w;
  w.attach(r);
  r.jog(A, +1);
  r.run_for(0.04);
  CHECK(r.axis(A).phase == Phase::unlock);
  CHECK(r.axis(A).busy);
  CHECK(r.actual(A) == 100);
  r.run_for(0.3);
  CHECK(r.axis(A).phase == Phase::jog);
  CHECK(r.actual(A) > 100);
  r.release_jogs();
  r.run_until([&] { return r.axis(A).phase == Phase::lock; }, 2);
  CHECK(r.engine.outputs().axes[A].indexer_unlock == false);
  CHECK(r.axis(A).velocity_mm_per_s == 0);
  r.run_until([&] { return r.axis(A).phase == Phase::idle; }, 2);
  CHECK(r.sim().indexer_locked(A));
  CHECK_FALSE(r.axis(A).busy);
  CHECK_FALSE(w.moved_while_locked);
  CHECK_FALSE(w.motion_without_unlock);
  CHECK_FALSE(r.status().alarm);
}

SCENARIO("a move on an indexer axis reaches its target between an unlock and a lock", "[indexer]") {
  Rig r = indexer_rig();
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.step();
  LockWatch w;
  w.attach(r);
  r.move(A, 90);
  CHECK(r.status().last_command_result == CommandResult::accepted);
  CHECK(r.axis(A).phase == Phase::unlock);
  r.run_until([&] { return r.axis(A).phase == Phase::idle && r.sim().indexer_locked(A); }, 10);
  CHECK(r.axis(A).position_mm == Approx(90).margin(1e-9));
  CHECK(r.actual(A) == Approx(100 + 90).margin(1e-9));  // not homed: the carriage started at machine 0
  CHECK(w.saw_lock);
  CHECK_FALSE(w.moved_while_locked);
  CHECK_FALSE(w.motion_without_unlock);
}

SCENARIO("the final move of a cycle runs unlocked and the axis locks only after it", "[indexer]") {
  Rig r = indexer_rig();
  r.settings.axes[A].final_move_enable = true;
  r.settings.axes[A].final_position_mm = 30;
  r.step();
  LockWatch w;
  w.attach(r);
  bool locked_before_final = false;
  bool pulled_off = false;
  auto inner = r.on_period;
  r.on_period = [&](Rig& rig) {
    inner(rig);
    pulled_off = pulled_off || rig.axis(A).phase == Phase::pull_off;
    // Between the pull-off and the final move the axis stays unlocked.
    if (pulled_off && rig.status().homing && rig.sim().indexer_locked(A)) locked_before_final = true;
  };
  r.home_all();
  // Busy (state moving) until the indexer has locked after the final move.
  CHECK(r.axis(A).phase == Phase::lock);
  CHECK(r.status().state == MachineState::moving);
  r.run_until([&] { return r.sim().indexer_locked(A) && r.axis(A).phase == Phase::done; }, 2);
  CHECK(r.status().state == MachineState::homed);
  CHECK(r.actual(A) == Approx(30 + 1.05).margin(0.01));  // final position plus the release edge's offset
  CHECK_FALSE(locked_before_final);
  CHECK_FALSE(w.moved_while_locked);
  CHECK_FALSE(w.motion_without_unlock);
}

SCENARIO("nothing moves while the indexer never reports unlocked: homing, jog and move are held", "[indexer]") {
  Rig r = indexer_rig();
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.settings.axes[A].lock_timeout_ms = 60'000;  // no alarm in this test: only the hold
  r.machine.axes[A].fault = sim::Fault::indexer_stuck_locked;
  r.step();
  LockWatch w;
  w.attach(r);
  r.clear_trace();
  WHEN("homing") {
    r.pending.home_all = true;
    r.run_for(1);
  }
  WHEN("jogging") {
    r.jog(A, -1);
    r.run_for(1);
  }
  WHEN("moving") {
    r.move(A, 50);
    r.run_for(1);
  }
  CHECK(r.axis(A).phase == Phase::unlock);
  CHECK(r.engine.outputs().axes[A].indexer_unlock);
  CHECK(r.trace[A].path_mm == 0);
  CHECK(r.axis(A).velocity_mm_per_s == 0);
  CHECK_FALSE(w.moved_while_locked);
  CHECK_FALSE(r.status().alarm);
}

SCENARIO("an axis without indexer_lock never drives the unlock output and is not held", "[indexer]") {
  Rig r;
  r.machine.indexer[0] = true;  // fitted but not configured: the pin stays in
  bool unlock = false;
  r.on_period = [&](Rig& rig) { unlock = unlock || rig.engine.outputs().axes[0].indexer_unlock; };
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.step();
  r.move(0, 50);
  r.run_for(0.2);
  CHECK(r.axis(0).phase == Phase::move);
  CHECK_FALSE(unlock);
  CHECK(r.sim().moved_while_locked(0));  // the simulator sees the steps lost against the pin
}

SCENARIO("the rule set refuses an indexer on a gantry and a lock_timeout_ms of 0", "[indexer][settings]") {
  Settings s;
  s.axes[0] = typical_axis();
  s.axes[1] = typical_axis();
  s.axes[1].slave_of = 1;  // Y slave of X
  s.axes[0].indexer_lock = true;
  s.axes[0].lock_timeout_ms = 500;
  auto f = check_axis(s, 0);
  REQUIRE(f);
  CHECK(f->rule == CheckRule::indexer_in_gantry);
  CHECK(f->field == AxisField::indexer_lock);
  CHECK(describe_fault(*f, s).find("axis.x.indexer_lock") == 0);
  s.axes[0].indexer_lock = false;
  s.axes[1].indexer_lock = true;
  s.axes[1].lock_timeout_ms = 500;
  f = check_axis(s, 1);
  REQUIRE(f);
  CHECK(f->rule == CheckRule::indexer_in_gantry);
  s.axes[1].slave_of = 0;
  CHECK_FALSE(check_axis(s, 1));
  s.axes[1].lock_timeout_ms = 0;
  f = check_axis(s, 1);
  REQUIRE(f);
  CHECK(f->field == AxisField::lock_timeout_ms);
  CHECK(f->rule == CheckRule::not_positive);
}

SCENARIO("the simulated indexer holds the carriage while its pin is in and moves the pin after its delays",
         "[indexer][sim]") {
  sim::MachineConfig m;
  for (auto& a : m.axes) a = typical_sim_axis();
  m.indexer[A] = true;
  m.axes[A].unlock_delay_ms = 20;
  m.axes[A].lock_delay_ms = 30;
  sim::Simulator s(m);
  CHECK(s.indexer_locked(A));
  CHECK_FALSE(s.inputs().axes[A].indexer_unlocked);
  Outputs out;
  out.axes[A].motion = velocity_command(10, 0);
  out.axes[A].motor.velocity_mm_per_s = 10;
  out.axes[A].motor.position_mm = 100;
  s.advance(out, 0.001);
  CHECK(s.actual_position_mm(A) == 100);
  CHECK(s.moved_while_locked(A));
  Outputs rest;
  rest.axes[A].indexer_unlock = true;
  for (int i = 0; i < 15; ++i) s.advance(rest, 0.001);
  CHECK_FALSE(s.inputs().axes[A].indexer_unlocked);
  for (int i = 0; i < 10; ++i) s.advance(rest, 0.001);
  CHECK(s.inputs().axes[A].indexer_unlocked);
  CHECK_FALSE(s.indexer_locked(A));
  out.axes[A].indexer_unlock = true;
  s.advance(out, 0.001);
  CHECK(s.actual_position_mm(A) > 100);
  CHECK_FALSE(s.moved_while_locked(A));
  Outputs lock;  // unlock off, at rest
  for (int i = 0; i < 25; ++i) s.advance(lock, 0.001);
  CHECK(s.inputs().axes[A].indexer_unlocked);
  for (int i = 0; i < 10; ++i) s.advance(lock, 0.001);
  CHECK_FALSE(s.inputs().axes[A].indexer_unlocked);
  CHECK(s.indexer_locked(A));
}

// Found by the campaign (every indexer fault hid the home switch's edge times,
// as a sensor fault does, so the engine placed edges mid-period and homed up
// to half a period's travel off): an indexer fault leaves the switch alone.
SCENARIO("an indexer fault on the simulator leaves the home switch's edges and their times reported",
         "[indexer][sim]") {
  for (const sim::Fault f : {sim::Fault::indexer_stuck_locked, sim::Fault::indexer_never_locks}) {
    DYNAMIC_SECTION("fault " << name_of(f)) {
      sim::MachineConfig m;
      for (auto& a : m.axes) a = typical_sim_axis();
      m.axes[0].actual_position_mm = 0.5;
      m.axes[0].fault = f;
      sim::Simulator s(m);
      Outputs out;
      out.axes[0].motion = velocity_command(-10, 0);
      out.axes[0].motor.velocity_mm_per_s = -10;
      out.axes[0].motor.position_mm = 0.5;
      s.advance(out, 0.1);  // crosses the cam edge at 0 after 50 ms
      REQUIRE(s.inputs().axes[0].sensor_level);
      REQUIRE(s.inputs().axes[0].sensor_edges.count == 1);
      CHECK(s.inputs().axes[0].sensor_edges.time_s[0] == Approx(0.05).margin(1e-9));
    }
  }
}

SCENARIO("a lock that engages under a running motor unhomes its axis even when alarms keep the homed state",
         "[indexer]") {
  Rig r = indexer_rig();
  r.settings.global.alarm_clears_homed = false;
  r.step();
  r.pending.home_all = true;
  r.step();
  r.run_until([&] { return r.axis(A).phase == Phase::done && r.sim().indexer_locked(A); }, 60);
  REQUIRE(r.axis(A).homed);
  WHEN("the pin drops in while A jogs") {
    r.jog(A, +1);
    r.run_until([&] { return r.axis(A).velocity_mm_per_s > 0; }, 1);
    r.run_for(0.05);
    r.set_fault(A, sim::Fault::indexer_stuck_locked);
    r.run_until([&] { return r.status().alarm; }, 1);
    THEN("lock_engaged, and A is no longer homed: its motor ran on against the pin") {
      CHECK(r.axis(A).alarm.code == AlarmCode::lock_engaged);
      CHECK_FALSE(r.axis(A).homed);
    }
  }
  WHEN("a held jog ends at A's soft limit") {
    r.settings.axes[A].soft_limits_enable = true;
    r.settings.axes[A].soft_limit_max_mm = 2;
    r.jog(A, +1);
    r.run_until([&] { return r.axis(A).position_mm == 2 && r.axis(A).velocity_mm_per_s == 0; }, 5);
    REQUIRE(r.axis(A).phase != Phase::jog);  // ended: the indexer locks (phase lock, then idle)
    r.run_until([&] { return r.sim().indexer_locked(A); }, 5);
    THEN("A rests and locks there, homed, with no alarm: nothing ran against the pin") {
      CHECK(r.sim().indexer_locked(A));
      CHECK_FALSE(r.status().alarm);
      CHECK(r.axis(A).homed);
      CHECK(r.axis(A).position_mm == 2);
    }
    r.release_jogs();
  }
}

// Drive-performed homing moves the carriage without the module's steps, so
// the indexer holds the home request back as it holds steps: a drive asked
// to home against the pin would lose its position or break the pin.
SCENARIO("drive mode on an indexer axis: the home request waits until the axis is unlocked", "[indexer][drive]") {
  Rig r = indexer_rig();
  r.settings.axes[A].mode = HomingMode::drive;
  r.settings.axes[A].drive_home_timeout_s = 30;
  r.step();
  REQUIRE(r.sim().indexer_locked(A));
  bool request_while_locked = false, request_seen = false, moved_while_locked = false;
  r.on_period = [&](Rig& rig) {
    const bool request = rig.engine.outputs().axes[A].drive_request;
    request_seen = request_seen || request;
    if (request && (rig.sim().indexer_locked(A) || rig.axis(A).phase == Phase::unlock)) request_while_locked = true;
    moved_while_locked = moved_while_locked || rig.sim().moved_while_locked(A);
  };
  GIVEN("an indexer that unlocks in 50 ms") {
    r.pending.home_all = true;
    r.run_until([&] { return !r.status().homing; }, 60);
    r.run_until([&] { return r.sim().indexer_locked(A) && r.axis(A).phase == Phase::done; }, 2);
    THEN("the drive homes once unlocked, the axis is homed at the drive's home and locked again") {
      CHECK(request_seen);
      CHECK_FALSE(request_while_locked);
      CHECK_FALSE(moved_while_locked);
      CHECK_FALSE(r.status().alarm);
      CHECK(r.axis(A).homed);
      CHECK(r.actual(A) == Approx(0).margin(1e-9));
      CHECK(r.sim().indexer_locked(A));
    }
  }
  GIVEN("an indexer stuck locked") {
    r.set_fault(A, sim::Fault::indexer_stuck_locked);
    r.pending.home_all = true;
    r.run_until([&] { return r.status().alarm; }, 5);
    THEN("the unlock times out and the drive was never asked to home") {
      CHECK(r.axis(A).alarm.code == AlarmCode::unlock_not_confirmed);
      CHECK_FALSE(request_seen);
      CHECK(r.actual(A) == 100);
    }
  }
}

namespace {

// Homes every axis once and counts how often A's unlock output came on, from
// the cycle's start until A is locked again at rest.
int unlocks_in_one_home(Rig& r) {
  int unlocks = 0;
  bool was_on = r.engine.outputs().axes[A].indexer_unlock;
  r.on_period = [&](Rig& rig) {
    const bool on = rig.engine.outputs().axes[A].indexer_unlock;
    if (on && !was_on) ++unlocks;
    was_on = on;
  };
  r.pending.home_all = true;
  r.step();
  r.run_until([&] { return !r.status().homing; }, 60);
  r.run_until([&] { return r.sim().indexer_locked(A) && r.axis(A).phase == Phase::done; }, 2);
  r.on_period = nullptr;
  return unlocks;
}

// A homes with a final move to final_mm (manual: where it stands becomes
// 20; absolute_final: the encoder reads carriage + 7, home_position 2),
// its indexer locked before the cycle.
Rig final_move_rig(HomingMode mode, double final_mm, double carriage_mm, bool after_x = false) {
  Rig r = indexer_rig();
  if (after_x) {  // in the second sequence step, after X (homed by hand)
    r.settings.axes[0].mode = HomingMode::manual;
    r.settings.global.sequence_steps = {axis_bit(0), axis_bit(A), 0, 0, 0, 0};
  }
  AxisSettings& s = r.settings.axes[A];
  s.mode = mode;
  s.final_move_enable = true;
  s.final_position_mm = final_mm;
  s.home_position_mm = mode == HomingMode::manual ? 20 : 2;
  r.machine.axes[A].absolute_offset_mm = 7;
  r.machine.axes[A].actual_position_mm = carriage_mm;
  r.step();
  r.run_until([&] { return r.sim().indexer_locked(A); }, 2);
  return r;
}

}  // namespace

SCENARIO("an indexer axis already at its final position homes without pulsing its unlock output",
         "[indexer]") {
  // The axis stands at 20, its final position, so its final move has no
  // length: a real pin would be pulled and pushed back for nothing. Alone in
  // the sequence, or in its second step, when its cycle begins in the period
  // X's ends.
  for (const HomingMode mode : {HomingMode::manual, HomingMode::absolute_final}) {
    for (const bool after_x : {false, true}) {
      DYNAMIC_SECTION(mode_name(mode) << (after_x ? ", in the step after X" : ", alone")) {
        Rig r = final_move_rig(mode, 20, 15, after_x);
        CHECK(unlocks_in_one_home(r) == 0);
        CHECK(unlocks_in_one_home(r) == 0);  // and again
        CHECK(r.status().state == MachineState::homed);
        CHECK(r.axis(A).homed);
        CHECK(r.axis(A).position_mm == Approx(20).margin(1e-9));
        CHECK(r.sim().indexer_locked(A));
        CHECK(r.actual(A) == 15);
      }
    }
  }
}

SCENARIO("an indexer axis with a final move unlocks once per cycle and stays unlocked up to the final move",
         "[indexer]") {
  // Between the pull-off and the final move the axis rests while it assigns
  // its coordinate: the pin stays out (no lock and unlock in between).
  for (const HomingMode mode : {HomingMode::switch_release, HomingMode::manual, HomingMode::absolute_final}) {
    DYNAMIC_SECTION(mode_name(mode)) {
      Rig r = final_move_rig(mode, 40, mode == HomingMode::switch_release ? 100 : 15);
      CHECK(unlocks_in_one_home(r) == 1);
      CHECK(r.status().state == MachineState::homed);
      CHECK_FALSE(r.status().alarm);
      CHECK(r.axis(A).position_mm == Approx(40).margin(1e-6));
      CHECK(r.sim().indexer_locked(A));
    }
  }
}
