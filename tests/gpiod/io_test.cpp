// GpiodIo on the fake chip: edges latched from kernel timestamps, levels,
// outputs, and the safe state at exit.
#include <catch2/catch.hpp>

#include "backend_fixture.hpp"

using homing::Outputs;

namespace {
constexpr std::int64_t kMs = 1'000'000;
}

TEST_CASE("sensor edges carry their kernel time within the period, not the period's end") {
  fixture::Backend b;
  b.period(Outputs{}, 0);    // the control loop's first, empty period
  b.period(Outputs{}, kMs);  // anchors the timeline
  const std::int64_t start = b.now_ns;
  b.chip->play("X.home", start + 300'000, true);   // 0.3 ms into the next period
  b.chip->play("X.home", start + 450'000, false);  // bounce
  b.chip->play("X.home", start + 700'000, true);
  const auto in = b.period(Outputs{}, kMs);
  REQUIRE(in.axes[0].sensor_edges.count == 3);
  CHECK(in.axes[0].sensor_edges.time_s[0] == Approx(0.0003).margin(1e-9));
  CHECK(in.axes[0].sensor_edges.time_s[1] == Approx(0.00045).margin(1e-9));
  CHECK(in.axes[0].sensor_edges.time_s[2] == Approx(0.0007).margin(1e-9));
  CHECK(in.axes[0].sensor_level);
  CHECK(b.period(Outputs{}, kMs).axes[0].sensor_edges.count == 0);
}

TEST_CASE("a kernel stamping with CLOCK_REALTIME (before 5.7): edges still land at the right time") {
  fixture::Backend b;
  b.period(Outputs{}, kMs);
  const std::int64_t start = b.now_ns;
  b.chip->play("X.home", start + 250'000 + b.realtime_offset_ns, true);
  const auto in = b.period(Outputs{}, kMs);
  REQUIRE(in.axes[0].sensor_edges.count == 1);
  CHECK(in.axes[0].sensor_edges.time_s[0] == Approx(0.00025).margin(1e-9));
}

TEST_CASE("a late loop runs short periods at once: each edge goes to the period it happened in") {
  fixture::Backend b;
  b.period(Outputs{}, kMs);
  const std::int64_t start = b.now_ns;
  b.chip->play("X.home", start + 1'600'000, true);  // in the second third
  b.now_ns = start + 3 * kMs;                       // the loop wakes 3 ms later
  b.chip->now_ns = b.now_ns;
  homing::Inputs in[3];
  for (auto& i : in) {
    b.io->advance(Outputs{}, 0.001);
    i = b.io->read();
  }
  CHECK(in[0].axes[0].sensor_edges.count == 0);
  CHECK_FALSE(in[0].axes[0].sensor_level);
  REQUIRE(in[1].axes[0].sensor_edges.count == 1);
  CHECK(in[1].axes[0].sensor_edges.time_s[0] == Approx(0.0006).margin(1e-9));
  CHECK(in[2].axes[0].sensor_level);
}

TEST_CASE("a lost event: the level still follows, without an edge time (the engine places it mid-period)") {
  fixture::Backend b;
  b.period(Outputs{}, kMs);
  b.chip->set_level_silently("X.home", true);
  const auto in = b.period(Outputs{}, kMs);
  CHECK(in.axes[0].sensor_level);
  CHECK(in.axes[0].sensor_edges.count == 0);
  // The same level reported again by a late event is not a second edge.
  b.chip->play("X.home", b.now_ns + 100'000, true);
  CHECK(b.period(Outputs{}, kMs).axes[0].sensor_edges.count == 0);
}

TEST_CASE("index input: only rising edges are reported") {
  fixture::Backend b;
  b.period(Outputs{}, kMs);
  const std::int64_t start = b.now_ns;
  b.chip->play("X.index", start + 100'000, true);
  b.chip->play("X.index", start + 200'000, false);
  const auto in = b.period(Outputs{}, kMs);
  REQUIRE(in.axes[0].index_edges.count == 1);
  CHECK(in.axes[0].index_edges.time_s[0] == Approx(0.0001).margin(1e-9));
}

TEST_CASE("start button and permit are debounced, e-stop and drive fault act at once") {
  fixture::Backend b;
  b.period(Outputs{}, kMs);
  b.chip->set_level_silently("start_button", true);
  b.chip->set_level_silently("homing_permit", true);
  b.chip->set_level_silently("estop", true);
  b.chip->set_level_silently("drive_fault", true);
  auto in = b.period(Outputs{}, kMs);
  CHECK(in.estop);
  CHECK(in.axes[0].drive_fault);
  CHECK_FALSE(in.axes[1].drive_fault);  // not wired: no fault invented
  CHECK_FALSE(in.start_button);
  int periods = 1;
  while (!in.start_button && periods < 50) in = b.period(Outputs{}, kMs), ++periods;
  CHECK(periods == 11);  // 10 ms input_debounce_ms, sampled at the period ends
  CHECK(in.homing_permit);
  // A 3 ms glitch of the button is ignored.
  b.chip->set_level_silently("start_button", false);
  for (int i = 0; i < 3; ++i) CHECK(b.period(Outputs{}, kMs).start_button);
  b.chip->set_level_silently("start_button", true);
  for (int i = 0; i < 20; ++i) CHECK(b.period(Outputs{}, kMs).start_button);
}

TEST_CASE("enable, lamp, push and commutator follow the engine's outputs and are off after shutdown") {
  auto cfg = fixture::config();
  cfg.axes[0].push = homing::gpiod::LineSpec{"X.push", "gpiochip0", 6u};
  cfg.axes[0].commutator = homing::gpiod::LineSpec{"X.commutator", "gpiochip0", 7u};
  fixture::Backend b(cfg);
  CHECK_FALSE(b.chip->value("X.enable"));  // requested inactive: motors off until the engine says so
  Outputs out{};
  out.axes[0].enable = true;
  out.axes[0].push_output = true;
  out.axes[0].commutator_output = true;
  out.homing_done_lamp = true;
  b.period(out, kMs);
  CHECK(b.chip->value("X.enable"));
  CHECK(b.chip->value("X.push"));
  CHECK(b.chip->value("X.commutator"));
  CHECK(b.chip->value("homing_done_lamp"));
  b.io->shutdown();
  CHECK_FALSE(b.chip->value("X.enable"));
  CHECK_FALSE(b.chip->value("X.push"));
  CHECK_FALSE(b.chip->value("X.commutator"));
  CHECK_FALSE(b.chip->value("homing_done_lamp"));
  CHECK_FALSE(b.chip->value("X.step"));
}

TEST_CASE("a step line that cannot be written reports a drive fault on its axis") {
  fixture::Backend b;
  b.period(Outputs{}, kMs);
  b.chip->fail_writes("X.step");
  Outputs out{};
  out.axes[0].motion = homing::velocity_command(10, 0);
  for (int i = 0; i < 5; ++i) b.period(out, kMs);
  CHECK(b.period(out, kMs).axes[0].drive_fault);
}

TEST_CASE("a period's pulses start at the instant the engine's period began, not a period and a half later") {
  fixture::Backend b;
  b.period(Outputs{}, 0);    // the control loop's first, empty period
  b.period(Outputs{}, kMs);  // anchors the timeline
  CHECK(b.io->playback_delay_ns() == 0);
  Outputs out{};
  out.axes[0].motion = homing::velocity_command(10, 0);  // 10 mm/s x 400 steps/mm: 4 steps per ms
  b.period(out, kMs);  // applied right after the engine's step, then the period runs
  CHECK(b.io->generator(0)->position_steps() == 4);  // where the engine's motion is at the period's end
  out.axes[0].motor = homing::integrate(out.axes[0].motor, out.axes[0].motion, 0.001);
  b.period(out, kMs);
  CHECK(b.io->generator(0)->position_steps() == 8);
}

TEST_CASE("playback_delay_us shifts the pulses later by that much") {
  auto cfg = fixture::config();
  cfg.playback_delay_us = 500;
  fixture::Backend b(cfg);
  b.period(Outputs{}, 0);
  b.period(Outputs{}, kMs);
  Outputs out{};
  out.axes[0].motion = homing::velocity_command(10, 0);
  b.period(out, kMs);
  CHECK(b.io->generator(0)->position_steps() == 2);  // half of the period played
}
