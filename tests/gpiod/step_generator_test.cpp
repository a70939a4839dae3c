// The step pulse generator, ticked with synthetic times: pulse counts and
// spacing, direction changes with set-up time, and the step count equal to
// the engine's position after any motion.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "fake_chip.hpp"
#include "homing/gpiod/step_generator.hpp"

using namespace homing;
using namespace homing::gpiod;

namespace {

constexpr std::int64_t kTickNs = 10'000;
constexpr std::int64_t kSetupNs = 5'000;

struct Axis {
  fake::Chip chip;
  LineId step, dir;
  std::unique_ptr<StepGenerator> gen;
  std::int64_t now_ns = 0;

  explicit Axis(double steps_per_unit) {
    step = *chip.request_output(LineSpec{"X.step", "gpiochip0", 1u}, false);
    dir = *chip.request_output(LineSpec{"X.dir", "gpiochip0", 2u}, false);
    chip.writes.clear();
    gen = std::make_unique<StepGenerator>(chip, step, dir, steps_per_unit, kSetupNs);
  }
  void run_until(std::int64_t end_ns) {
    while (now_ns + kTickNs <= end_ns) {
      now_ns += kTickNs;
      chip.now_ns = now_ns;
      gen->tick(now_ns);
    }
  }
  std::vector<fake::Write> rising_steps() const {
    std::vector<fake::Write> out;
    for (const auto& w : chip.writes_of("X.step"))
      if (w.value) out.push_back(w);
    return out;
  }
};

// The engine's side: one segment per period, motor integrated with the same
// motion function, handed over right after the engine's step, kStepNs into
// the period (as GpiodIo::apply() gets it), starting at the period's start.
struct EngineSide {
  static constexpr std::int64_t kStepNs = 60'000;  // the engine's step and the input reads
  MotionState motor{};
  std::int64_t t_ns = 0;
  void period(Axis& axis, const MotionCommand& cmd, std::int64_t dt_ns) {
    axis.run_until(t_ns + kStepNs);  // the previous segment runs on meanwhile
    axis.gen->push(Segment{t_ns, motor, cmd});
    axis.run_until(t_ns + dt_ns);
    motor = integrate(motor, cmd, static_cast<double>(dt_ns) * 1e-9);
    t_ns += dt_ns;
  }
};

}  // namespace

TEST_CASE("constant velocity: one step per 1/(v*steps_per_unit), evenly spaced, dir positive") {
  Axis axis(100);  // 100 steps/mm at 10 mm/s: 1000 steps/s
  EngineSide e;
  for (int i = 0; i < 1000; ++i) e.period(axis, velocity_command(10, 0), 1'000'000);
  const auto steps = axis.rising_steps();
  CHECK(axis.gen->position_steps() == 1000);
  REQUIRE(steps.size() == 1000);
  for (std::size_t i = 1; i < steps.size(); ++i) CHECK(std::llabs(steps[i].time_ns - steps[i - 1].time_ns - 1'000'000) <= kTickNs);
  // Direction set once, before the first step, by at least the set-up time.
  const auto dirs = axis.chip.writes_of("X.dir");
  REQUIRE(dirs.size() == 1);
  CHECK(dirs[0].value);
  CHECK(steps[0].time_ns - dirs[0].time_ns >= kSetupNs);
  // Each pulse is high for one tick.
  for (const auto& w : axis.chip.writes_of("X.step"))
    if (!w.value) CHECK(std::any_of(steps.begin(), steps.end(), [&](const auto& r) { return w.time_ns - r.time_ns == kTickNs; }));
}

TEST_CASE("a trapezoidal move ends with exactly round(position * steps_per_unit) steps emitted") {
  const double spu = GENERATE(80.0, 400.0, 3200.0 / 7.0);
  const double target = GENERATE(12.3456, -7.77);
  Axis axis(spu);
  EngineSide e;
  for (int i = 0; i < 3000; ++i) e.period(axis, move_to_command(e.motor, target, 10, 200, 0.001), 1'000'000);
  axis.run_until(e.t_ns + 10'000'000);
  REQUIRE(e.motor.position_mm == Approx(target).margin(1e-9));
  CHECK(axis.gen->position_steps() == std::llround(e.motor.position_mm * spu));
  CHECK(static_cast<std::int64_t>(axis.rising_steps().size()) == std::llabs(axis.gen->position_steps()));
  CHECK(axis.gen->max_lag_steps() <= 1);
}

TEST_CASE("direction changes: dir switches while step is low, and the next step waits the set-up time") {
  Axis axis(200);
  EngineSide e;
  for (int i = 0; i < 200; ++i) e.period(axis, velocity_command(5, 1000), 1'000'000);
  for (int i = 0; i < 400; ++i) e.period(axis, velocity_command(-5, 1000), 1'000'000);
  for (int i = 0; i < 400; ++i) e.period(axis, move_to_command(e.motor, 0, 5, 1000, 0.001), 1'000'000);
  REQUIRE(e.motor.velocity_mm_per_s == 0);
  axis.run_until(e.t_ns + 5'000'000);
  CHECK(axis.gen->position_steps() == std::llround(e.motor.position_mm * 200));
  const auto dirs = axis.chip.writes_of("X.dir");
  REQUIRE(dirs.size() >= 3);  // +, -, + (back to 0)
  const auto all = axis.chip.writes_of("X.step");
  for (const auto& d : dirs) {
    // The step line is low when dir changes, and stays low for the set-up time.
    bool high = false;
    for (const auto& w : all)
      if (w.time_ns <= d.time_ns) high = w.value;
    CHECK_FALSE(high);
    for (const auto& w : all)
      if (w.value && w.time_ns > d.time_ns) {
        CHECK(w.time_ns - d.time_ns >= kSetupNs);
        break;
      }
  }
  // Counting the pulses with the dir level at each rising edge gives the count.
  std::int64_t counted = 0;
  bool dir = false;
  std::size_t di = 0;
  for (const auto& w : all) {
    while (di < dirs.size() && dirs[di].time_ns <= w.time_ns) dir = dirs[di++].value;
    if (w.value) counted += dir ? 1 : -1;
  }
  CHECK(counted == axis.gen->position_steps());
}

TEST_CASE("late and jittery control periods: segments play back to back, no step lost or invented") {
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::int64_t> dt(700'000, 3'500'000);
  Axis axis(400);
  EngineSide e;
  for (int i = 0; i < 400; ++i) e.period(axis, velocity_command(i < 200 ? 20 : -3, 400), dt(rng));
  for (int i = 0; i < 2000; ++i) e.period(axis, move_to_command(e.motor, 1.0, 20, 400, 0.001), dt(rng));
  axis.run_until(e.t_ns + 10'000'000);
  CHECK(axis.gen->position_steps() == std::llround(e.motor.position_mm * 400));
  CHECK(axis.gen->position_steps() == 400);
}

TEST_CASE("a segment not yet handed over when its time comes: the previous command is extended") {
  Axis axis(100);
  axis.gen->push(Segment{0, MotionState{}, velocity_command(10, 0)});
  axis.run_until(3'000'000);  // 3 ms with only the first segment: 30 steps
  CHECK(axis.gen->position_steps() == 3);
  // The engine integrated the same command for a 3 ms period: the next one starts there.
  axis.gen->push(Segment{3'000'000, MotionState{0.03, 10}, stop_command(0)});
  axis.run_until(10'000'000);
  CHECK(axis.gen->position_steps() == 3);
}

TEST_CASE("a write error on the step line stops the generator and is reported") {
  Axis axis(100);
  axis.chip.fail_writes("X.step");
  axis.gen->push(Segment{0, MotionState{}, velocity_command(10, 0)});
  axis.run_until(1'000'000);
  CHECK(axis.gen->failed());
  CHECK_THAT(axis.gen->failure(), Catch::Contains("X.step") && Catch::Contains("gpiochip0 line 1"));
  CHECK(axis.gen->position_steps() == 0);
}
