// How far one control period advances the machine when the loop comes late:
// a time-scaled simulator catches up at most ControlLoop::kSimCatchUpMaxS of
// the wall clock (else a computer too slow for --time-scale makes every
// period longer than the last and commands wait seconds for the next one);
// real hardware always advances by the whole wall time. Stepped by hand.
#include <catch2/catch.hpp>

#include <memory>

#include "homing/machine_io.hpp"
#include "homing/sim/simulator_io.hpp"
#include "registers/defaults.hpp"
#include "registers/sim_bindings.hpp"
#include "server/control_loop.hpp"

namespace {

constexpr int kPeriodUs = 1000;
constexpr double kTimeScale = 20;

server::ControlLoop simulated_loop() {
  return server::ControlLoop(registers::default_settings(),
                             std::make_unique<homing::sim::SimulatorIo>(registers::default_sim_config()), kPeriodUs,
                             kTimeScale);
}

double simulated_s(const server::ControlLoop& loop) { return loop.snapshot().machine_time_s; }

// A real machine as far as the loop can tell (no simulator controls): it
// only adds up the time it is told has passed.
struct ClockedMachine final : homing::MachineIo {
  double* elapsed_s;
  explicit ClockedMachine(double* elapsed) : elapsed_s(elapsed) {}
  void advance(const homing::Outputs&, double dt_s) override { *elapsed_s += dt_s; }
  homing::Inputs read() override { return {}; }
};

}  // namespace

TEST_CASE("a time-scaled simulator on time advances by the wall time since the last period times the scale") {
  server::ControlLoop loop = simulated_loop();
  const double before = simulated_s(loop);
  loop.run_period(0.001);
  CHECK(simulated_s(loop) - before == Approx(0.001 * kTimeScale));
  loop.run_period(server::ControlLoop::kSimCatchUpMaxS);  // late, but within what a period catches up
  CHECK(simulated_s(loop) - before == Approx((0.001 + server::ControlLoop::kSimCatchUpMaxS) * kTimeScale));
}

TEST_CASE("a time-scaled simulator far behind the wall clock advances one period by the catch-up bound only, "
          "however late the period") {
  server::ControlLoop loop = simulated_loop();
  const double bound_s = server::ControlLoop::kSimCatchUpMaxS * kTimeScale;
  double before = simulated_s(loop);
  loop.run_period(2.0);  // what a sanitized build saw: a period 2 s after the last
  CHECK(simulated_s(loop) - before == Approx(bound_s));
  before = simulated_s(loop);
  loop.run_period(30.0);  // and the next, had it caught up 40 s of simulated time
  CHECK(simulated_s(loop) - before == Approx(bound_s));
  // The figures say so (published every 64 periods).
  for (int i = 0; i < 64; ++i) loop.run_period(0.001);
  CHECK(loop.stats().sim_held_back_periods == 2);
}

TEST_CASE("real hardware is never held back: a late period advances it by the whole wall time") {
  double elapsed_s = 0;
  server::ControlLoop loop(registers::default_settings(), std::make_unique<ClockedMachine>(&elapsed_s), kPeriodUs, 1.0);
  const double before = elapsed_s;
  loop.run_period(2.0);
  CHECK(elapsed_s - before == Approx(2.0));
  for (int i = 0; i < 64; ++i) loop.run_period(0.001);
  CHECK(loop.stats().sim_held_back_periods == 0);
}
