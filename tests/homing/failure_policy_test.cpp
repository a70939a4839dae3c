// The failure policy of a homing cycle (global.failure_policy): what the other
// axes do when one fails or the cycle is aborted, on a machine that homes Z in
// step 1, then X with the Y/A gantry (A software-slaved to Y) in step 2, and B
// in step 3. Whatever the policy, the first alarm stays the one reported, an
// e-stop stops everything, and nothing moves that the policy does not move.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>

#include "homing/motion.hpp"
#include "rig.hpp"

using namespace rig;

namespace {

constexpr std::size_t X = 0, Y = 1, Z = 2, A = 3, B = 4;
constexpr std::array<std::size_t, 5> kAxes{X, Y, Z, A, B};

// Seek 20 mm/s at 500 mm/s²: a stop takes 0.4 mm, plus a period of travel.
constexpr double kStop_mm = 0.4 + 20 * 0.001 + 1e-6;

Rig machine(FailurePolicy policy) {
  Rig r;
  for (std::size_t a : kAxes) r.settings.axes[a] = typical_axis();
  r.settings.axes[A].slave_of = static_cast<std::uint8_t>(Y + 1);
  r.settings.axes[A].slave_mode = SlaveMode::own_output;
  r.settings.axes[A].kind = AxisKind::linear;
  r.settings.axes[B].kind = AxisKind::linear;
  r.settings.global.sequence_steps = {axis_bit(Z), static_cast<AxisMask>(axis_bit(X) | axis_bit(Y)), axis_bit(B), 0, 0, 0};
  r.settings.global.failure_policy = policy;
  r.machine.axes[Z].actual_position_mm = 40;
  r.machine.axes[A].actual_position_mm = 100.5;  // the gantry starts 0.5 mm out of square
  return r;
}

// X cannot find its sensor: its seek ends after 50 mm (2.5 s into step 2),
// while Y and A are still seeking theirs 100 mm away.
void x_sensor_out_of_reach(Rig& r) { r.settings.axes[X].max_seek_travel_mm = 50; }

// Runs until X latches its alarm; the carriage positions at that moment.
std::array<double, kAxisCount> until_alarm_on(Rig& r, std::size_t a) {
  REQUIRE(r.run_until([&] { return bool(r.axis(a).alarm); }, 60));
  std::array<double, kAxisCount> at{};
  for (std::size_t b = 0; b < kAxisCount; ++b) at[b] = r.actual(b);
  return at;
}

void until_cycle_over(Rig& r) {
  REQUIRE(r.run_until([&] { return !r.status().homing; }, 120));
  r.run_until([&] { return !r.any_moving(); }, 5);
}

}  // namespace

SCENARIO("stop_all, the default: when X fails every axis stops and the following steps never start",
         "[failure_policy]") {
  Rig r = machine(FailurePolicy::stop_all);
  CHECK(Settings{}.global.failure_policy == FailurePolicy::stop_all);
  x_sensor_out_of_reach(r);
  r.pending.home_all = true;
  r.step();
  const auto at = until_alarm_on(r, X);
  r.clear_trace();
  until_cycle_over(r);
  THEN("X's alarm is the one reported and every axis came to rest within its stop") {
    CHECK(r.axis(X).alarm.code == AlarmCode::sensor_not_found);
    CHECK(r.status().first_alarm_axis == static_cast<std::int8_t>(X));
    CHECK(r.status().state == MachineState::alarm);
    for (std::size_t a : kAxes) CHECK(std::abs(r.actual(a) - at[a]) <= kStop_mm);
    CHECK(r.trace[B].path_mm == 0);
    CHECK(r.trace[Z].path_mm == 0);
    CHECK_FALSE(r.axis(Y).homed);
    CHECK(r.status().homing_cycles == 0);
  }
}

SCENARIO("finish_independent: when X fails, the Y/A gantry of the same step finishes homing and B's step never starts",
         "[failure_policy]") {
  Rig r = machine(FailurePolicy::finish_independent);
  x_sensor_out_of_reach(r);
  r.pending.home_all = true;
  r.step();
  const auto at = until_alarm_on(r, X);
  CHECK(r.status().homing);  // the step still runs
  r.clear_trace();
  until_cycle_over(r);
  THEN("X stopped where its alarm found it, with its own alarm reported") {
    CHECK(r.axis(X).alarm.code == AlarmCode::sensor_not_found);
    CHECK(r.axis(X).alarm.phase == Phase::seek);
    CHECK(r.status().first_alarm_axis == static_cast<std::int8_t>(X));
    CHECK(std::abs(r.actual(X) - at[X]) <= kStop_mm);
  }
  THEN("Y and A, independent of X, found their own edges and are homed, square") {
    CHECK(r.saw(Y, Phase::back_off));
    CHECK(r.saw(A, Phase::back_off));
    CHECK(r.axis(Y).homed);
    CHECK(r.axis(A).homed);
    CHECK_FALSE(r.axis(Y).alarm);
    CHECK(r.actual(Y) == Approx(1.05).margin(1e-3));
    CHECK(r.actual(A) == Approx(1.05).margin(1e-3));
  }
  THEN("nothing else moved: Z, done in step 1, stayed (unhomed by the alarm); B's step never started") {
    CHECK(r.trace[Z].path_mm == 0);
    CHECK_FALSE(r.axis(Z).homed);
    CHECK(r.trace[B].path_mm == 0);
    CHECK_FALSE(r.saw(B, Phase::seek));
    CHECK(r.status().state == MachineState::alarm);
    CHECK_FALSE(r.status().homing);
    CHECK(r.status().homing_cycles == 0);
  }
}

SCENARIO("finish_independent: a gantry side's failure stops its partner while X, independent, finishes", "[failure_policy]") {
  Rig r = machine(FailurePolicy::finish_independent);
  r.step();
  r.set_fault(A, sim::Fault::sensor_stuck_inactive);  // A never finds its sensor: the pair racks
  r.pending.home_all = true;
  r.step();
  const auto at = until_alarm_on(r, A);
  r.clear_trace();
  until_cycle_over(r);
  THEN("the gantry stopped with the slave's alarm; X homed") {
    CHECK(r.axis(A).alarm.code == AlarmCode::misalignment);
    CHECK_FALSE(r.axis(Y).alarm);
    CHECK(std::abs(r.actual(Y) - at[Y]) <= kStop_mm);
    CHECK(std::abs(r.actual(A) - at[A]) <= kStop_mm);
    CHECK_FALSE(r.axis(Y).homed);
    CHECK(r.axis(X).homed);
    CHECK(r.actual(X) == Approx(1.05).margin(1e-3));
    CHECK(r.trace[B].path_mm == 0);
  }
}

SCENARIO("finish_independent: an axis of the step homed before the failure stays homed, the earlier step's does not",
         "[failure_policy]") {
  // X starts near its sensor and is done long before A's dead sensor racks the gantry.
  Rig r = machine(FailurePolicy::finish_independent);
  REQUIRE(r.settings.global.alarm_clears_homed);
  r.machine.axes[X].actual_position_mm = 20;
  r.step();
  r.set_fault(A, sim::Fault::sensor_stuck_inactive);
  r.pending.home_all = true;
  r.step();
  REQUIRE(r.run_until([&] { return r.axis(X).phase == Phase::done; }, 60));
  REQUIRE_FALSE(r.axis(A).alarm);
  until_alarm_on(r, A);
  until_cycle_over(r);
  CHECK(r.axis(X).homed);
  CHECK(r.axis(X).position_mm == Approx(0).margin(1e-9));
  CHECK_FALSE(r.axis(Z).homed);
  CHECK_FALSE(r.axis(Y).homed);
  CHECK_FALSE(r.axis(A).homed);
}

SCENARIO("finish_independent: when an axis that goes on fails too, the first alarm stays the one reported",
         "[failure_policy]") {
  // A's dead sensor racks the gantry about 5 s into step 2; X, further from
  // its sensor than its seek reaches, fails later (7.5 s).
  Rig r = machine(FailurePolicy::finish_independent);
  r.machine.axes[X].actual_position_mm = 200;
  r.settings.axes[X].max_seek_travel_mm = 150;
  r.step();
  r.set_fault(A, sim::Fault::sensor_stuck_inactive);
  r.pending.home_all = true;
  r.step();
  until_alarm_on(r, A);
  REQUIRE_FALSE(r.axis(X).alarm);
  until_cycle_over(r);
  CHECK(r.axis(X).alarm.code == AlarmCode::sensor_not_found);
  CHECK(r.axis(A).alarm.code == AlarmCode::misalignment);
  CHECK(r.status().first_alarm_axis == static_cast<std::int8_t>(A));
  CHECK(reported_alarm_axis(r.status()) == static_cast<int>(A));
}

SCENARIO("return_to_start: when X fails, the axes that moved go back to where the cycle found them, the last step first",
         "[failure_policy]") {
  // X's sensor is stuck active: it backs off max_backoff (10 mm at 1 mm/s)
  // and fails not_released, while the gantry, 300 mm from its sensors, still seeks.
  Rig r = machine(FailurePolicy::return_to_start);
  r.machine.axes[Y].actual_position_mm = 300;
  r.machine.axes[A].actual_position_mm = 300.5;
  r.settings.axes[Y].max_seek_travel_mm = 400;
  r.step();
  r.set_fault(X, sim::Fault::sensor_stuck_active);
  std::array<double, kAxisCount> start{};
  for (std::size_t a = 0; a < kAxisCount; ++a) start[a] = r.actual(a);
  r.pending.home_all = true;
  r.step();
  until_alarm_on(r, X);
  REQUIRE(r.axis(X).alarm.code == AlarmCode::not_released);
  REQUIRE(r.axis(Y).phase == Phase::return_to_start);
  REQUIRE(r.actual(Y) < 200);  // it was seeking
  r.clear_trace();
  until_cycle_over(r);
  THEN("X, Y, A and Z are back at their starts; the gantry with its start's skew") {
    for (std::size_t a : {X, Y, A, Z}) CHECK(r.actual(a) == Approx(start[a]).margin(1e-6));
    CHECK(r.actual(A) - r.actual(Y) == Approx(0.5).margin(1e-6));
    for (std::size_t a : {X, Y, A, Z}) CHECK(r.saw(a, Phase::return_to_start));
  }
  THEN("step 2 went back first, then Z, which step 1 had homed") {
    REQUIRE(r.trace[Z].first_move_period > 0);
    CHECK(r.trace[Z].first_move_period > r.trace[X].last_move_period);
    CHECK(r.trace[Z].first_move_period > r.trace[Y].last_move_period);
    CHECK(r.trace[Z].first_move_period > r.trace[A].last_move_period);
  }
  THEN("B never moved, X's alarm is still the one reported, the cycle is not counted") {
    CHECK(r.trace[B].path_mm == 0);
    CHECK(r.axis(X).alarm.code == AlarmCode::not_released);
    CHECK(r.status().first_alarm_axis == static_cast<std::int8_t>(X));
    for (std::size_t a : {Y, Z, A, B}) CHECK_FALSE(r.axis(a).alarm);
    CHECK(r.status().state == MachineState::alarm);
    CHECK(r.status().homing_cycles == 0);
    for (std::size_t a : kAxes) CHECK(r.axis(a).phase == Phase::idle);
  }
  THEN("no axis that went back is homed; after a reset the machine homes again") {
    for (std::size_t a : {X, Y, A, Z}) CHECK_FALSE(r.axis(a).homed);
    r.set_fault(X, sim::Fault::none);
    r.reset_alarm();
    CHECK(r.home_all());
  }
}

SCENARIO("return_to_start: an axis whose seek ran out without its sensor stays, the others go back", "[failure_policy]") {
  // Its seek may have met the mechanical stop and lost steps there: a way
  // back by counted steps would not end where it started.
  Rig r = machine(FailurePolicy::return_to_start);
  x_sensor_out_of_reach(r);
  r.step();
  std::array<double, kAxisCount> start{};
  for (std::size_t a = 0; a < kAxisCount; ++a) start[a] = r.actual(a);
  r.pending.home_all = true;
  r.step();
  const auto at = until_alarm_on(r, X);
  until_cycle_over(r);
  CHECK(r.axis(X).alarm.code == AlarmCode::sensor_not_found);
  CHECK(std::abs(r.actual(X) - at[X]) <= kStop_mm);
  CHECK(r.axis(X).phase == Phase::idle);
  for (std::size_t a : {Y, A, Z}) CHECK(r.actual(a) == Approx(start[a]).margin(1e-6));
}

SCENARIO("return_to_start: an axis the cycle found on a limit switch stays, the others go back", "[failure_policy][limits]") {
  // Z rests on its positive limit switch and homes away from it: its way
  // back would end on the switch it stood on (campaign seed 162: the way
  // back met the switch and stopped every axis).
  Rig r = machine(FailurePolicy::return_to_start);
  r.settings.axes[Z].limits_fitted = true;
  r.settings.axes[Z].limit_overtravel_mm = 1;
  r.machine.axes[Z].limit_min_mm = -8;
  r.machine.axes[Z].hard_stop_min_mm = -10;
  r.machine.axes[Z].limit_max_mm = 39.5;
  x_sensor_out_of_reach(r);
  r.step();
  REQUIRE(r.sim().limit_active(Z, true));
  std::array<double, kAxisCount> start{};
  for (std::size_t a = 0; a < kAxisCount; ++a) start[a] = r.actual(a);
  r.pending.home_all = true;
  r.step();
  REQUIRE(r.status().last_command_result == CommandResult::accepted);
  REQUIRE(r.run_until([&] { return r.status().sequence_step == 2; }, 60));
  const double z_homed_at = r.actual(Z);
  until_alarm_on(r, X);
  until_cycle_over(r);
  CHECK(r.axis(X).alarm.code == AlarmCode::sensor_not_found);
  CHECK(r.status().first_alarm_axis == static_cast<std::int8_t>(X));
  CHECK(r.actual(Z) == Approx(z_homed_at).margin(1e-9));
  CHECK_FALSE(r.sim().limit_active(Z, true));
  for (std::size_t a : {Y, A}) CHECK(r.actual(a) == Approx(start[a]).margin(1e-6));
  CHECK_FALSE(r.axis(Z).alarm);
}

SCENARIO("return_to_start with alarm_clears_homed off: Z, homed in step 1, goes back and is no longer homed",
         "[failure_policy]") {
  Rig r = machine(FailurePolicy::return_to_start);
  r.settings.global.alarm_clears_homed = false;
  x_sensor_out_of_reach(r);
  r.pending.home_all = true;
  r.step();
  REQUIRE(r.run_until([&] { return r.status().sequence_step == 2; }, 60));
  REQUIRE(r.axis(Z).homed);
  until_alarm_on(r, X);
  until_cycle_over(r);
  CHECK(r.actual(Z) == Approx(40).margin(1e-6));
  CHECK_FALSE(r.axis(Z).homed);
}

SCENARIO("return_to_start: an axis whose drive faulted does not move, the others go back", "[failure_policy]") {
  Rig r = machine(FailurePolicy::return_to_start);
  r.step();
  std::array<double, kAxisCount> start{};
  for (std::size_t a = 0; a < kAxisCount; ++a) start[a] = r.actual(a);
  r.pending.home_all = true;
  r.step();
  REQUIRE(r.run_until([&] { return r.status().sequence_step == 2 && r.axis(X).phase == Phase::seek; }, 60));
  r.run_for(1.0);
  r.set_fault(X, sim::Fault::drive_fault);
  const auto at = until_alarm_on(r, X);
  until_cycle_over(r);
  CHECK(r.axis(X).alarm.code == AlarmCode::drive_fault);
  CHECK(std::abs(r.actual(X) - at[X]) <= kStop_mm);
  for (std::size_t a : {Y, A, Z}) CHECK(r.actual(a) == Approx(start[a]).margin(1e-6));
}

SCENARIO("return_to_start: a racked gantry stays where its guard stopped it, the others go back", "[failure_policy]") {
  Rig r = machine(FailurePolicy::return_to_start);
  r.step();
  std::array<double, kAxisCount> start{};
  for (std::size_t a = 0; a < kAxisCount; ++a) start[a] = r.actual(a);
  r.set_fault(A, sim::Fault::sensor_stuck_inactive);
  r.pending.home_all = true;
  r.step();
  const auto at = until_alarm_on(r, A);
  r.clear_trace();
  until_cycle_over(r);
  CHECK(r.axis(A).alarm.code == AlarmCode::misalignment);
  CHECK(std::abs(r.actual(Y) - at[Y]) <= kStop_mm);
  CHECK(std::abs(r.actual(A) - at[A]) <= kStop_mm);
  CHECK(std::abs((r.actual(A) - r.actual(Y)) - 0.5) <= r.settings.axes[A].max_misalignment_mm + 1e-3);
  for (std::size_t a : {X, Z}) CHECK(r.actual(a) == Approx(start[a]).margin(1e-6));
  CHECK(r.trace[B].path_mm == 0);
}

SCENARIO("return_to_start: an abort brakes every axis at once, they go back, a second abort stops the way back",
         "[failure_policy]") {
  Rig r = machine(FailurePolicy::return_to_start);
  r.step();
  std::array<double, kAxisCount> start{};
  for (std::size_t a = 0; a < kAxisCount; ++a) start[a] = r.actual(a);
  r.pending.home_all = true;
  r.step();
  REQUIRE(r.run_until([&] { return r.status().sequence_step == 2 && r.axis(X).phase == Phase::seek; }, 60));
  r.run_for(1.0);
  r.pending.abort = true;
  r.step();
  CHECK(r.axis(X).alarm.code == AlarmCode::aborted);
  CHECK(r.status().last_command_result == CommandResult::accepted);
  WHEN("nothing else happens") {
    // Braking starts in the period of the abort: speeds only fall until all rest.
    double v_prev = std::abs(r.axis(X).velocity_mm_per_s);
    REQUIRE(r.run_until([&] {
      const double v = std::abs(r.axis(X).velocity_mm_per_s);
      CHECK(v <= v_prev + 1e-9);
      v_prev = v;
      return v == 0;
    }, 5));
    until_cycle_over(r);
    THEN("every axis that moved is back at its start") {
      for (std::size_t a : {X, Y, A, Z}) CHECK(r.actual(a) == Approx(start[a]).margin(1e-6));
    }
  }
  WHEN("the operator aborts again while the axes go back") {
    REQUIRE(r.run_until([&] { return r.axis(X).phase == Phase::return_to_start && r.axis(X).velocity_mm_per_s != 0; }, 5));
    r.run_for(0.5);
    std::array<double, kAxisCount> at{};
    for (std::size_t a = 0; a < kAxisCount; ++a) at[a] = r.actual(a);
    r.pending.abort = true;
    r.step();
    THEN("they stop where they are, the first alarm unchanged, and the cycle is over") {
      CHECK_FALSE(r.status().homing);
      r.clear_trace();
      r.run_for(1.0);
      for (std::size_t a : kAxes) CHECK(std::abs(r.actual(a) - at[a]) <= kStop_mm);
      CHECK(r.actual(X) != Approx(start[X]).margin(1));
      CHECK(r.trace[Z].path_mm == 0);
      CHECK(r.axis(X).alarm.code == AlarmCode::aborted);
      CHECK(r.status().first_alarm_axis == static_cast<std::int8_t>(X));
    }
  }
}

SCENARIO("return_to_start: a drive fault on an aborted axis going back stops every axis and its alarm stays aborted",
         "[failure_policy]") {
  Rig r = machine(FailurePolicy::return_to_start);
  r.pending.home_all = true;
  r.step();
  REQUIRE(r.run_until([&] { return r.status().sequence_step == 2 && r.axis(X).phase == Phase::seek; }, 60));
  r.run_for(1.0);
  r.pending.abort = true;
  r.step();
  REQUIRE(r.run_until([&] { return r.axis(Y).phase == Phase::return_to_start && r.axis(Y).velocity_mm_per_s > 0; }, 5));
  r.run_for(0.3);
  r.set_fault(Y, sim::Fault::drive_fault);
  r.step();
  r.step();
  CHECK_FALSE(r.status().homing);
  std::array<double, kAxisCount> at{};
  for (std::size_t a = 0; a < kAxisCount; ++a) at[a] = r.actual(a);
  r.clear_trace();
  r.run_for(2.0);
  for (std::size_t a : kAxes) CHECK(std::abs(r.actual(a) - at[a]) <= kStop_mm);
  CHECK(r.axis(Y).alarm.code == AlarmCode::aborted);
  CHECK((r.status().interlocks & interlock::drive_fault) != 0);
  CHECK(r.trace[Z].path_mm == 0);
}

SCENARIO("return_to_start: axes that fail in the same period are one failure and the others still go back",
         "[failure_policy]") {
  // The drives of X and C (a copy of X in step 2) fault in the same period.
  Rig r = machine(FailurePolicy::return_to_start);
  constexpr std::size_t C = 5;
  r.settings.axes[C] = r.settings.axes[X];
  r.settings.axes[C].kind = AxisKind::linear;
  r.settings.global.sequence_steps[1] |= axis_bit(C);
  r.step();
  std::array<double, kAxisCount> start{};
  for (std::size_t a = 0; a < kAxisCount; ++a) start[a] = r.actual(a);
  r.pending.home_all = true;
  r.step();
  REQUIRE(r.run_until([&] { return r.status().sequence_step == 2 && r.axis(X).phase == Phase::seek; }, 60));
  r.run_for(1.0);
  r.set_fault(X, sim::Fault::drive_fault);
  r.set_fault(C, sim::Fault::drive_fault);
  const auto at = until_alarm_on(r, X);
  CHECK(r.axis(C).alarm.code == AlarmCode::drive_fault);
  until_cycle_over(r);
  for (std::size_t a : {X, C}) CHECK(std::abs(r.actual(a) - at[a]) <= kStop_mm);
  for (std::size_t a : {Y, A, Z}) CHECK(r.actual(a) == Approx(start[a]).margin(1e-6));
}

SCENARIO("finish_independent: an abort stops every axis (each is the aborted one)", "[failure_policy]") {
  Rig r = machine(FailurePolicy::finish_independent);
  r.pending.home_all = true;
  r.step();
  REQUIRE(r.run_until([&] { return r.status().sequence_step == 2 && r.axis(X).phase == Phase::seek; }, 60));
  r.run_for(1.0);
  std::array<double, kAxisCount> at{};
  for (std::size_t a = 0; a < kAxisCount; ++a) at[a] = r.actual(a);
  r.pending.abort = true;
  r.step();
  CHECK_FALSE(r.status().homing);
  r.run_for(2.0);
  for (std::size_t a : kAxes) CHECK(std::abs(r.actual(a) - at[a]) <= kStop_mm);
  for (std::size_t a : {X, Y, A}) CHECK(r.axis(a).alarm.code == AlarmCode::aborted);
  CHECK_FALSE(r.axis(Y).homed);
}

SCENARIO("a reset while a failed cycle winds down is refused busy and changes nothing", "[failure_policy]") {
  for (FailurePolicy p : {FailurePolicy::finish_independent, FailurePolicy::return_to_start}) {
    DYNAMIC_SECTION(name_of(p)) {
      Rig r = machine(p);
      x_sensor_out_of_reach(r);
      r.pending.home_all = true;
      r.step();
      until_alarm_on(r, X);
      r.reset_alarm();
      CHECK(r.status().last_command_result == CommandResult::refused_busy);
      CHECK(r.axis(X).alarm.code == AlarmCode::sensor_not_found);
      CHECK(r.status().homing);
    }
  }
}

SCENARIO("an e-stop stops everything whatever the policy, also while a failed cycle winds down", "[failure_policy]") {
  for (FailurePolicy p : {FailurePolicy::stop_all, FailurePolicy::finish_independent, FailurePolicy::return_to_start}) {
    DYNAMIC_SECTION(name_of(p) << ": pressed after X failed") {
      Rig r = machine(p);
      x_sensor_out_of_reach(r);
      r.pending.home_all = true;
      r.step();
      until_alarm_on(r, X);
      // Under return_to_start: once the way back has begun.
      if (p == FailurePolicy::return_to_start)
        REQUIRE(r.run_until([&] { return r.axis(Y).phase == Phase::return_to_start && r.axis(Y).velocity_mm_per_s > 0; }, 5));
      r.run_for(0.2);
      std::array<double, kAxisCount> at{};
      for (std::size_t a = 0; a < kAxisCount; ++a) at[a] = r.actual(a);
      r.sim().set_estop(true);
      r.step();
      r.step();
      CHECK_FALSE(r.status().homing);
      CHECK(r.status().global_alarm == AlarmCode::emergency_stop);
      r.clear_trace();
      r.run_for(3.0);
      for (std::size_t a : kAxes) CHECK(std::abs(r.actual(a) - at[a]) <= kStop_mm);
      CHECK(r.axis(X).alarm.code == AlarmCode::sensor_not_found);
      CHECK(r.status().first_alarm_axis == static_cast<std::int8_t>(X));
      CHECK_FALSE(r.axis(Y).homed);
    }
    DYNAMIC_SECTION(name_of(p) << ": pressed first, in step 2") {
      Rig r = machine(p);
      r.pending.home_all = true;
      r.step();
      REQUIRE(r.run_until([&] { return r.status().sequence_step == 2 && r.axis(X).phase == Phase::seek; }, 60));
      r.run_for(1.0);
      std::array<double, kAxisCount> at{};
      for (std::size_t a = 0; a < kAxisCount; ++a) at[a] = r.actual(a);
      r.sim().set_estop(true);
      r.step();
      r.step();
      CHECK_FALSE(r.status().homing);
      r.run_for(3.0);
      for (std::size_t a : kAxes) CHECK(std::abs(r.actual(a) - at[a]) <= kStop_mm);
      for (std::size_t a : {X, Y, A}) CHECK(r.axis(a).alarm.code == AlarmCode::emergency_stop);
      CHECK_FALSE(r.axis(Y).homed);
    }
  }
}
