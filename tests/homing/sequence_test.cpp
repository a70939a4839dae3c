// The homing sequence: steps as bit masks run in order, axes of one step move
// together, axes in no step are assigned at the end; single-axis homing; the
// start button and the homing-done lamp.
#include <catch2/catch.hpp>

#include <set>

#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

namespace {
constexpr std::size_t X = 0, Y = 1, Z = 2, A = 3;
}

SCENARIO("sequence steps run in order, the axes of one step moving together", "[sequence]") {
  GIVEN("a mill: Z in step 1, X and Y in step 2") {
    Rig r;
    r.add_axis(Y, 2);
    r.add_axis(Z, 1);
    r.settings.global.sequence_steps = {axis_bit(Z), static_cast<AxisMask>(axis_bit(X) | axis_bit(Y)), 0, 0, 0, 0};
    r.machine.axes[Y].actual_position_mm = 60;
    r.machine.axes[Z].actual_position_mm = 30;
    std::vector<int> steps_seen;
    r.on_period = [&](Rig& rr) {
      const int st = rr.status().sequence_step;
      if (st && (steps_seen.empty() || steps_seen.back() != st)) steps_seen.push_back(st);
      if (st == 1) {
        CHECK(rr.axis(X).phase == Phase::waiting);
        CHECK(rr.axis(Y).phase == Phase::waiting);
      }
    };
    r.step();
    r.clear_trace();
    REQUIRE(r.home_all());
    THEN("Z moved and finished before X and Y started") {
      CHECK(steps_seen == std::vector<int>{1, 2});
      REQUIRE(r.trace[Z].first_move_period > 0);
      CHECK(r.trace[Z].last_move_period < r.trace[X].first_move_period);
      CHECK(r.trace[X].first_move_period == r.trace[Y].first_move_period);
      for (std::size_t a : {X, Y, Z}) {
        CHECK(r.axis(a).homed);
        CHECK(r.actual(a) == Approx(1.05).margin(1e-4));
      }
    }
  }
}

SCENARIO("empty sequence steps are skipped", "[sequence]") {
  Rig r;
  r.add_axis(Z, 2);
  r.settings.global.sequence_steps = {0, axis_bit(Z), 0, axis_bit(X), 0, 0};
  std::set<int> steps_seen;
  r.on_period = [&](Rig& rr) { steps_seen.insert(rr.status().sequence_step); };
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK(steps_seen == std::set<int>{0, 2, 4});
  CHECK(r.trace[Z].last_move_period < r.trace[X].first_move_period);
}

SCENARIO("an axis in no step is assigned its home position when the sequence ends", "[sequence]") {
  Rig r;
  r.settings.axes[A] = typical_axis();  // configured, but in no step
  r.settings.axes[A].home_position_mm = 7;
  r.machine.axes[A].actual_position_mm = 42;
  bool a_homed_during_cycle = false;
  r.on_period = [&](Rig& rr) {
    if (rr.status().homing && rr.axis(A).homed) a_homed_during_cycle = true;
  };
  r.step();
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK_FALSE(a_homed_during_cycle);
  CHECK(r.axis(A).homed);
  CHECK(r.axis(A).position_mm == Approx(7).margin(1e-9));
  CHECK(r.trace[A].path_mm == 0);
}

SCENARIO("an axis in no step keeps its coordinate in later home-alls: jog, home-all, jog does not creep", "[sequence]") {
  Rig r;
  r.settings.axes[A] = typical_axis();  // configured, but in no step
  r.settings.axes[A].mode = HomingMode::manual;
  r.settings.axes[A].home_position_mm = 7;
  r.machine.axes[A].actual_position_mm = 42;
  r.step();
  REQUIRE(r.home_all());
  REQUIRE(r.axis(A).position_mm == Approx(7).margin(1e-9));
  // Jog A 5 mm further, then home-all twice: its coordinate follows the carriage.
  r.move(A, 12);
  REQUIRE(r.run_until([&] { return !r.any_moving() && r.axis(A).position_mm > 11.9; }, 30));
  const double actual_at_12 = r.actual(A);
  REQUIRE(r.home_all());
  CHECK(r.axis(A).position_mm == Approx(12).margin(1e-6));
  REQUIRE(r.home_all());
  CHECK(r.axis(A).position_mm == Approx(12).margin(1e-6));
  CHECK(r.axis(A).homed);
  // The same coordinate still names the same place: back to 7 is where it was assigned.
  r.move(A, 7);
  REQUIRE(r.run_until([&] { return !r.any_moving() && r.axis(A).position_mm < 7.1; }, 30));
  CHECK(r.actual(A) == Approx(42).margin(1e-6));
  CHECK(actual_at_12 == Approx(47).margin(1e-6));
  // Named alone, it is assigned afresh where it stands.
  r.move(A, 10);
  REQUIRE(r.run_until([&] { return !r.any_moving() && r.axis(A).position_mm > 9.9; }, 30));
  REQUIRE(r.home_axes(axis_bit(A)));
  CHECK(r.axis(A).position_mm == Approx(7).margin(1e-9));
}

SCENARIO("an unhomed axis in no step is assigned again in a home-all", "[sequence]") {
  Rig r;
  r.settings.axes[A] = typical_axis();
  r.settings.axes[A].mode = HomingMode::manual;
  r.settings.axes[A].home_position_mm = 7;
  r.step();
  REQUIRE(r.home_all());
  r.move(A, 15);
  REQUIRE(r.run_until([&] { return !r.any_moving() && r.axis(A).position_mm > 14.9; }, 30));
  // An alarm clears the homed state (global.alarm_clears_homed, default on).
  r.set_fault(A, sim::Fault::drive_fault);
  r.run_for(0.05);
  REQUIRE(r.status().alarm);
  r.set_fault(A, sim::Fault::none);
  r.run_for(0.05);
  r.reset_alarm();
  r.run_for(0.05);
  REQUIRE_FALSE(r.status().alarm);
  REQUIRE_FALSE(r.axis(A).homed);
  REQUIRE(r.home_all());
  CHECK(r.axis(A).position_mm == Approx(7).margin(1e-9));
}

SCENARIO("homing a single axis moves only that axis", "[sequence]") {
  Rig r;
  r.add_axis(Y, 1);
  r.machine.axes[Y].actual_position_mm = 80;
  r.step();
  r.clear_trace();
  REQUIRE(r.home_axes(axis_bit(Y)));
  CHECK(r.axis(Y).homed);
  CHECK(r.actual(Y) == Approx(1.05).margin(1e-4));
  CHECK(r.trace[X].path_mm == 0);
  CHECK_FALSE(r.axis(X).homed);
  CHECK(r.status().state == MachineState::not_homed);
  CHECK_FALSE(r.engine.outputs().homing_done_lamp);
}

SCENARIO("the start button starts home-all and the lamp shows homing done", "[sequence]") {
  Rig r;
  r.step();
  CHECK_FALSE(r.engine.outputs().homing_done_lamp);
  r.sim().set_start_button(true);
  r.step();
  CHECK(r.status().homing);
  CHECK(r.status().last_command_result == CommandResult::accepted);
  r.sim().set_start_button(false);
  r.run_until([&] { return !r.status().homing; }, 60);
  CHECK(r.status().state == MachineState::homed);
  CHECK(r.engine.outputs().homing_done_lamp);
  CHECK(r.status().homing_cycles == 1);
  WHEN("an alarm is latched the lamp goes off") {
    r.sim().set_estop(true);
    r.step();
    CHECK_FALSE(r.engine.outputs().homing_done_lamp);
  }
}

SCENARIO("a start button held at power-up starts nothing until it is released and pressed again",
         "[sequence]") {
  Rig r;
  r.sim().set_start_button(true);
  r.run_for(0.5);
  CHECK_FALSE(r.status().homing);
  CHECK(r.status().homing_cycles == 0);
  CHECK(r.trace[0].path_mm == 0);
  r.sim().set_start_button(false);
  r.run_for(0.05);
  r.sim().set_start_button(true);
  r.run_until([&] { return r.status().homing; }, 1);
  CHECK(r.status().homing);
}

SCENARIO("a held start button starts one cycle, not one per period", "[sequence]") {
  Rig r;
  r.step();  // the press comes after start-up
  r.sim().set_start_button(true);
  r.run_until([&] { return r.status().homing; }, 1);
  r.run_until([&] { return !r.status().homing; }, 60);
  r.run_for(0.5);
  CHECK(r.status().homing_cycles == 1);
  CHECK_FALSE(r.status().homing);
}

SCENARIO("commands while a cycle runs: the same one is already running, another is refused busy",
         "[sequence][commands]") {
  Rig r;
  r.add_axis(Y, 1);
  r.pending.home_all = true;
  r.step();
  REQUIRE(r.status().homing);
  r.run_for(0.1);
  r.pending.home_all = true;
  r.step();
  CHECK(r.status().last_command_result == CommandResult::already_running);
  r.pending.home_axes = axis_bit(Y);
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_busy);
  r.move(Z, 5);
  CHECK(r.status().last_command_result == CommandResult::refused_busy);
  r.jog(Z, 1);
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_busy);
  r.release_jogs();
  r.run_until([&] { return !r.status().homing; }, 60);
  CHECK(r.status().state == MachineState::homed);
}

SCENARIO("a slave whose master is in no step is assigned its home position with its master", "[sequence][gantry]") {
  Rig r;
  r.settings.axes[A] = typical_axis();  // a master in no step
  r.settings.axes[A].home_position_mm = 7;
  r.settings.axes[4] = typical_axis();
  r.settings.axes[4].slave_of = static_cast<std::uint8_t>(A + 1);
  r.settings.axes[4].home_position_mm = 7;
  r.step();
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK(r.axis(A).homed);
  CHECK(r.axis(4).homed);
  CHECK(r.axis(4).position_mm == Approx(7).margin(1e-9));
  CHECK(r.trace[4].path_mm == 0);
}

SCENARIO("homing named axes moves exactly those, in one cycle, in the order of their sequence steps",
         "[sequence][home_axes]") {
  GIVEN("Z in step 1, X in step 2, Y in step 3") {
    Rig r;
    r.add_axis(Y, 3);
    r.add_axis(Z, 1);
    r.settings.global.sequence_steps = {axis_bit(Z), axis_bit(X), axis_bit(Y), 0, 0, 0};
    r.machine.axes[Y].actual_position_mm = 60;
    r.machine.axes[Z].actual_position_mm = 30;
    std::vector<int> steps_seen;
    r.on_period = [&](Rig& rr) {
      const int st = rr.status().sequence_step;
      if (st && (steps_seen.empty() || steps_seen.back() != st)) steps_seen.push_back(st);
    };
    r.step();
    r.clear_trace();
    WHEN("X and Y are named in one command") {
      REQUIRE(r.home_axes(static_cast<AxisMask>(axis_bit(X) | axis_bit(Y))));
      THEN("one cycle homes X, then Y, and Z does not move") {
        CHECK(r.status().homing_cycles == 1);
        CHECK(steps_seen == std::vector<int>{1, 2});  // the cycle's steps, numbered without gaps
        CHECK(r.axis(X).homed);
        CHECK(r.axis(Y).homed);
        CHECK(r.actual(X) == Approx(1.05).margin(1e-4));
        CHECK(r.actual(Y) == Approx(1.05).margin(1e-4));
        REQUIRE(r.trace[Y].first_move_period > 0);
        CHECK(r.trace[X].last_move_period < r.trace[Y].first_move_period);
        CHECK_FALSE(r.axis(Z).homed);
        CHECK(r.trace[Z].path_mm == 0);
        CHECK(r.actual(Z) == 30);
      }
    }
  }
}

SCENARIO("a named axis in no sequence step homes by its mode after the named axes that are in a step",
         "[sequence][home_axes]") {
  Rig r;
  r.settings.axes[A] = typical_axis();  // configured, in no step
  r.machine.axes[A].actual_position_mm = 40;
  r.step();
  r.clear_trace();
  REQUIRE(r.home_axes(static_cast<AxisMask>(axis_bit(X) | axis_bit(A))));
  CHECK(r.status().homing_cycles == 1);
  CHECK(r.axis(A).homed);
  CHECK(r.actual(A) == Approx(1.05).margin(1e-4));  // it sought its sensor: not assigned where it stood
  REQUIRE(r.trace[A].first_move_period > 0);
  CHECK(r.trace[X].last_move_period < r.trace[A].first_move_period);
}

TEST_CASE("the plan of named axes follows the sequence steps, keeps gantry partners together and ends with the rest",
          "[sequence][home_axes]") {
  Settings s;
  for (std::size_t a : {X, Y, Z, A}) s.axes[a] = typical_axis();
  s.axes[Y].slave_of = X + 1;  // Y is X's gantry slave
  s.global.sequence_steps = {axis_bit(Z), axis_bit(X), 0, 0, 0, 0};
  const CyclePlan named = plan_cycle(s, static_cast<AxisMask>(axis_bit(Y) | axis_bit(Z) | axis_bit(A)), false);
  CHECK(named.steps[0] == axis_bit(Z));
  CHECK(named.steps[1] == (axis_bit(X) | axis_bit(Y)));  // naming the slave homes the pair
  CHECK(named.steps[2] == axis_bit(A));                  // in no step: last
  CHECK(named.steps[3] == 0);
  CHECK(named.unsequenced == 0);
  const CyclePlan one = plan_cycle(s, axis_bit(X), false);
  CHECK(one.steps[0] == (axis_bit(X) | axis_bit(Y)));
  CHECK(one.covered() == (axis_bit(X) | axis_bit(Y)));
}

TEST_CASE("a home correction is a measurement only when the axis was homed when its cycle started",
          "[sequence][statistics]") {
  Rig r;
  r.step();
  CHECK_FALSE(r.axis(X).homed_at_cycle_start);
  // The first cycle after start-up corrects by where the axis stood and says it was not homed.
  REQUIRE(r.home_all());
  CHECK_FALSE(r.axis(X).homed_at_cycle_start);
  CHECK(std::abs(r.axis(X).home_correction_mm) > 50);
  // The next cycle starts homed: its correction measures the sensor.
  REQUIRE(r.home_all());
  CHECK(r.axis(X).homed_at_cycle_start);
  CHECK(std::abs(r.axis(X).home_correction_mm) < 0.01);
  // An alarm clears the homed state (alarm_clears_homed): the next cycle is not trusted again.
  r.sim().set_estop(true);
  r.step();
  r.sim().set_estop(false);
  r.step();
  r.reset_alarm();
  REQUIRE_FALSE(r.axis(X).homed);
  REQUIRE(r.home_all());
  CHECK_FALSE(r.axis(X).homed_at_cycle_start);
}

TEST_CASE("a homing command is judged by what blocks it, in one order for the engine and the Modbus side",
          "[sequence][commands]") {
  using namespace interlock;
  CHECK(homing_refusal_of(0) == CommandResult::accepted);
  CHECK(homing_refusal_of(not_homed) == CommandResult::accepted);
  CHECK(homing_refusal_of(estop | alarm_latched) == CommandResult::refused_estop);
  CHECK(homing_refusal_of(drive_fault | alarm_latched) == CommandResult::refused_drive_fault);
  CHECK(homing_refusal_of(alarm_latched) == CommandResult::refused_alarm);
  CHECK(homing_refusal_of(settings_lost) == CommandResult::refused_alarm);
  CHECK(homing_refusal_of(communication_lost | permit_missing) == CommandResult::refused_communication_lost);
  CHECK(homing_refusal_of(permit_missing | homing_active) == CommandResult::refused_no_permit);
  CHECK(homing_refusal_of(homing_active) == CommandResult::refused_busy);
  CHECK(homing_refusal_of(motion_active) == CommandResult::refused_busy);
}
