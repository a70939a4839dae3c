// The pulse thread on its own clock (the one test of this folder that runs in
// real time): it sleeps while every step generator rests, so an idle machine
// costs no tick, and steps again as soon as the control thread hands over a
// segment that moves.
#include <catch2/catch.hpp>

#include <chrono>
#include <thread>

#include "fake_chip.hpp"
#include "homing/gpiod/pulse_thread.hpp"
#include "homing/gpiod/step_generator.hpp"

using namespace homing;
using namespace homing::gpiod;
using namespace std::chrono_literals;

namespace {

// The thread's turns once they stopped growing for three looks 10 ms apart
// (a thread held off its core for 10 ms on a busy machine does not pass for
// asleep); bounded: 2 s.
std::uint64_t settled_turns(const PulseThread& t) {
  std::uint64_t last = t.turns();
  int quiet = 0;
  for (int i = 0; i < 200 && quiet < 3; ++i) {
    std::this_thread::sleep_for(10ms);
    const std::uint64_t now = t.turns();
    quiet = now == last ? quiet + 1 : 0;
    last = now;
  }
  return last;
}

template <typename Pred>
bool within_5_s(Pred pred) {
  for (int i = 0; i < 500 && !pred(); ++i) std::this_thread::sleep_for(10ms);
  return pred();
}

}  // namespace

TEST_CASE("the pulse thread sleeps while every step generator rests and steps again as soon as a segment moves") {
  fake::Chip chip;
  const LineId step = *chip.request_output(LineSpec{"X.step", "gpiochip0", 1u}, false);
  const LineId dir = *chip.request_output(LineSpec{"X.dir", "gpiochip0", 2u}, false);
  StepGenerator gen(chip, step, dir, 100.0, 0);
  PulseThread thread({&gen}, 20'000, 0);  // a tick of 20 us: 50,000 a second if it never slept
  REQUIRE(thread.start().empty());

  // Nothing handed over: at rest from the start.
  const std::uint64_t idle = settled_turns(thread);
  std::this_thread::sleep_for(100ms);
  CHECK(thread.turns() == idle);

  // 1 mm at 10 mm/s: 100 steps, then the engine's next segments at rest there.
  gen.push(Segment{monotonic_now_ns(), MotionState{0, 0}, MotionCommand{10, 0, true, 1.0}});
  thread.wake();
  CHECK(within_5_s([&] { return gen.position_steps() == 100; }));
  CHECK(thread.turns() > idle + 100);  // at least a rising and a falling tick per step
  gen.push(Segment{monotonic_now_ns(), MotionState{1.0, 0}, MotionCommand{}});
  thread.wake();

  const std::uint64_t rested = settled_turns(thread);
  std::this_thread::sleep_for(100ms);
  CHECK(thread.turns() == rested);
  CHECK(gen.position_steps() == 100);
  CHECK_FALSE(gen.failed());
  thread.stop();  // joins a sleeping thread
}

TEST_CASE("a step generator rests only once its step line is low, its position reached and its motion at rest") {
  fake::Chip chip;
  const LineId step = *chip.request_output(LineSpec{"X.step", "gpiochip0", 1u}, false);
  const LineId dir = *chip.request_output(LineSpec{"X.dir", "gpiochip0", 2u}, false);
  StepGenerator gen(chip, step, dir, 100.0, 0);
  std::int64_t now = 0;
  auto tick = [&] {
    now += 10'000;
    gen.tick(now);
  };
  tick();
  CHECK(gen.resting());  // nothing handed over
  // A segment that starts later: waiting for it is not rest.
  gen.push(Segment{50'000, MotionState{0, 0}, MotionCommand{}});
  tick();
  CHECK_FALSE(gen.resting());
  // Stands still at 0: rest.
  for (int i = 0; i < 5; ++i) tick();
  CHECK(gen.resting());
  // A move of 0.02 mm (2 steps) at 10 mm/s, held at its limit: not at rest
  // while it steps, nor while its command still asks for speed.
  gen.push(Segment{now, MotionState{0, 0}, MotionCommand{10, 0, true, 0.02}});
  tick();
  CHECK_FALSE(gen.resting());  // step line high
  for (int i = 0; i < 400; ++i) tick();
  CHECK(gen.position_steps() == 2);
  CHECK_FALSE(gen.resting());
  // The next segment at rest there, and another queued behind it.
  gen.push(Segment{now, MotionState{0.02, 0}, MotionCommand{}});
  gen.push(Segment{now + 100'000, MotionState{0.02, 0}, MotionCommand{}});
  tick();
  CHECK_FALSE(gen.resting());  // one still to play
  for (int i = 0; i < 20; ++i) tick();
  CHECK(gen.resting());
}
