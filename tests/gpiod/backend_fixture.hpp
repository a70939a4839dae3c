#pragma once
// A GpiodIo on a fake chip with a synthetic clock: tests set the time, play
// input events and step the pulse generators themselves.
#include <memory>
#include <toml++/toml.h>

#include "fake_chip.hpp"
#include "homing/gpiod/config.hpp"
#include "homing/gpiod/gpiod_io.hpp"

namespace fixture {

using namespace homing::gpiod;

// One axis wired as in README.md, plus every global signal.
inline constexpr const char* kConfig = R"(
[gpiod]
chip = "gpiochip0"
tick_us = 20
dir_setup_us = 5
input_debounce_ms = 10
estop = { line = 17, active_low = true, bias = "pull-up" }
drive_fault = 27
start_button = { line = "START", active_low = true }
homing_permit = 22
homing_done_lamp = 5

[gpiod.axes.X]
steps_per_unit = 400
step = 23
dir = 24
enable = { line = 25, active_low = true }
home = { line = 4, bias = "pull-up" }
index = 12
)";

inline BackendConfig config(const char* text = kConfig) {
  auto c = parse_config(toml::parse(text), "test.toml");
  if (!c) throw std::logic_error(c.error());
  return *c;
}

inline std::unique_ptr<fake::Chip> chip() {
  auto c = std::make_unique<fake::Chip>();
  c->chips["gpiochip0"].names[30] = "START";
  return c;
}

struct Backend {
  fake::Chip* chip = nullptr;
  std::unique_ptr<GpiodIo> io;
  std::int64_t now_ns = 1'000'000'000;  // CLOCK_MONOTONIC, synthetic
  std::int64_t realtime_offset_ns = 1'700'000'000'000'000'000;

  explicit Backend(const BackendConfig& cfg = config(), std::unique_ptr<fake::Chip> c = fixture::chip()) {
    chip = c.get();
    RunOptions run;
    run.control_period_us = 1000;
    run.start_pulse_thread = false;
    run.clocks.monotonic_ns = [this] { return now_ns; };
    run.clocks.realtime_ns = [this] { return now_ns + realtime_offset_ns; };
    auto opened = GpiodIo::open(cfg, std::move(c), run);
    if (!opened) throw std::logic_error(opened.error());
    io = std::move(*opened);
  }
  // One control-loop period of dt that runs `outputs`, as the loop does it:
  // apply(outputs) at its start (right after the engine's step that computed
  // them), the pulse generators ticked through [now, now + dt), then
  // advance(outputs, dt) and read() at its end.
  homing::Inputs period(const homing::Outputs& outputs, std::int64_t dt_ns, std::int64_t tick_ns = 20'000) {
    io->apply(outputs);
    const std::int64_t end = now_ns + dt_ns;
    while (now_ns + tick_ns <= end) tick(now_ns + tick_ns);
    now_ns = end;
    chip->now_ns = now_ns;
    io->advance(outputs, static_cast<double>(dt_ns) * 1e-9);
    return io->read();
  }
  virtual void tick(std::int64_t t_ns) {
    now_ns = t_ns;
    chip->now_ns = t_ns;
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (auto* g = io->generator(a)) g->tick(t_ns);
  }
  virtual ~Backend() = default;
};

}  // namespace fixture
