// The engine driving the GPIO backend on a fake machine: a carriage that
// moves by the emitted steps and a home switch that plays timestamped,
// bouncing events. Home-all is started by the start button; the lamp lights.
#include <catch2/catch.hpp>

#include <map>

#include "backend_fixture.hpp"
#include "homing/engine.hpp"

using namespace homing;

namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr double kSwitchMm = -5.0;  // the switch is active below this carriage position

struct Machine : fixture::Backend {
  std::map<std::int64_t, bool> scheduled;  // input events still to happen
  bool active = false;
  int bounces = 0;
  double first_edge_mm = 0;
  bool seen_edge = false;
  bool prev_start = false;

  void tick(std::int64_t t) override {
    fixture::Backend::tick(t);
    const double carriage = static_cast<double>(io->generator(0)->position_steps()) / 400.0;
    const bool now_active = carriage <= kSwitchMm;
    if (now_active != active) {
      active = now_active;
      chip->play("X.home", t, active);
      // Contact bounce: two more toggles within 0.6 ms.
      for (int i = 1; i <= 2 * bounces; ++i) scheduled[t + i * 300'000] = (i % 2 == 0) == active;
    }
    while (!scheduled.empty() && scheduled.begin()->first <= t) {
      chip->play("X.home", scheduled.begin()->first, scheduled.begin()->second);
      scheduled.erase(scheduled.begin());
    }
  }
};

Settings settings() {
  Settings s;
  AxisSettings& x = s.axes[0];
  x.mode = HomingMode::switch_release;
  x.direction = Direction::negative;
  x.seek_feedrate_mm_per_min = 600;  // 10 mm/s
  x.latch_feedrate_mm_per_min = 60;  // 1 mm/s
  x.acceleration_mm_per_s2 = 500;
  x.max_seek_travel_mm = 50;
  x.max_stop_distance_mm = 10;
  x.max_backoff_mm = 10;
  x.pull_off_mm = 1;
  x.home_position_mm = 0;
  x.debounce_ms = 2;
  x.soft_limit_min_mm = -1;
  x.soft_limit_max_mm = 500;
  s.global.sequence_steps = {axis_bit(0), 0, 0, 0, 0, 0};
  return s;
}

}  // namespace

TEST_CASE("home-all from the start button through GPIO: bouncing switch, reference edge from timestamps, lamp") {
  const int bounces = GENERATE(0, 1);
  Machine m;
  m.bounces = bounces;
  Engine engine;
  const Settings s = settings();
  Outputs outputs{};
  auto period = [&](std::int64_t dt_ns) {
    const Inputs in = m.period(outputs, dt_ns);
    outputs = engine.step(s, in, static_cast<double>(dt_ns) * 1e-9).outputs;
  };
  period(0);  // as the control loop's constructor does
  // Press the start button (active-low: the line's logical value is what we play).
  m.chip->set_level_silently("start_button", true);
  for (int i = 0; i < 20; ++i) period(kMs);
  CHECK(engine.status().homing);
  m.chip->set_level_silently("start_button", false);
  bool done = false;
  for (int i = 0; i < 20'000 && !done; ++i) {
    period(kMs);
    done = engine.status().axes[0].homed && !engine.status().homing;
  }
  REQUIRE(done);
  REQUIRE_FALSE(engine.status().alarm);
  for (int i = 0; i < 10; ++i) period(kMs);  // the pulses catch up with the engine's last period
  CHECK(m.chip->value("homing_done_lamp"));
  CHECK(m.chip->value("X.enable"));
  // The release edge is at -5 mm (+ one step: the first step above it). The
  // pulses play where the engine computed them (no playback delay), so the
  // reference is the edge within one step, never moved by the debounce or
  // the bounce.
  const double reference = engine.status().axes[0].trigger_position_mm;
  CHECK(reference == Approx(kSwitchMm).margin(0.0025 + 1e-6));
  // The motor rests at the pulled-off point: steps emitted = round(position * steps_per_unit).
  CHECK(m.io->generator(0)->position_steps() ==
        std::llround((reference + s.axes[0].pull_off_mm) * 400.0));
}
