// Drive-performed homing on GPIO: each axis's home_request output follows the
// engine's drive_request and its home_done input reaches the engine (a level,
// debounced like the operator's inputs); the wiring check wants both lines
// for axis.<a>.mode = drive.
#include <catch2/catch.hpp>

#include "backend_fixture.hpp"

using homing::Outputs;
using namespace homing::gpiod;

namespace {
constexpr std::int64_t kMs = 1'000'000;

BackendConfig drive_wiring() {
  auto cfg = fixture::config();
  cfg.axes[0].home_request = homing::gpiod::LineSpec{"X.home_request", "gpiochip0", 8u};
  cfg.axes[0].home_done = homing::gpiod::LineSpec{"X.home_done", "gpiochip0", 9u};
  return cfg;
}

homing::Settings drive_settings() {
  homing::Settings s;
  s.axes[0].mode = homing::HomingMode::drive;
  s.axes[0].drive_home_timeout_s = 30;
  return s;
}
}  // namespace

TEST_CASE("the home_request line follows the engine's drive request and is off after shutdown") {
  fixture::Backend b(drive_wiring());
  CHECK_FALSE(b.chip->value("X.home_request"));
  Outputs out{};
  out.axes[0].drive_request = true;
  b.period(out, kMs);
  CHECK(b.chip->value("X.home_request"));
  out.axes[0].drive_request = false;
  b.period(out, kMs);
  CHECK_FALSE(b.chip->value("X.home_request"));
  out.axes[0].drive_request = true;
  b.period(out, kMs);
  REQUIRE(b.chip->value("X.home_request"));
  b.io->shutdown();
  CHECK_FALSE(b.chip->value("X.home_request"));
}

TEST_CASE("the home_done line reaches the engine as drive_done once it held for input_debounce_ms") {
  fixture::Backend b(drive_wiring());
  auto in = b.period(Outputs{}, kMs);
  CHECK_FALSE(in.axes[0].drive_done);
  b.chip->set_level_silently("X.home_done", true);
  int periods = 0;
  while (!in.axes[0].drive_done && periods < 50) in = b.period(Outputs{}, kMs), ++periods;
  CHECK(periods == 11);  // 10 ms input_debounce_ms, sampled at the period ends
  CHECK_FALSE(in.axes[1].drive_done);  // not wired: no done invented
  // A 3 ms drop is a glitch, not a lost reference.
  b.chip->set_level_silently("X.home_done", false);
  for (int i = 0; i < 3; ++i) CHECK(b.period(Outputs{}, kMs).axes[0].drive_done);
  b.chip->set_level_silently("X.home_done", true);
  for (int i = 0; i < 20; ++i) CHECK(b.period(Outputs{}, kMs).axes[0].drive_done);
  // A drop that holds is reported.
  b.chip->set_level_silently("X.home_done", false);
  periods = 0;
  while (in.axes[0].drive_done && periods < 50) in = b.period(Outputs{}, kMs), ++periods;
  CHECK(periods == 11);
}

TEST_CASE("the [gpiod] table takes home_request and home_done per axis") {
  const auto cfg = fixture::config(R"(
[gpiod]
chip = "gpiochip0"
[gpiod.axes.X]
steps_per_unit = 400
step = 23
dir = 24
home_request = 8
home_done = { line = 9, active_low = true }
)");
  REQUIRE(cfg.axes[0].home_request);
  REQUIRE(cfg.axes[0].home_done);
  CHECK(cfg.axes[0].home_request->role == "X.home_request");
  CHECK(cfg.axes[0].home_done->role == "X.home_done");
  CHECK_THROWS_WITH(fixture::config(R"(
[gpiod]
chip = "gpiochip0"
[gpiod.axes.X]
steps_per_unit = 400
step = 23
dir = 24
home_request = 8
home_done = 8
)"),
                    Catch::Contains("X.home_request (gpiochip0 line 8) and X.home_done (gpiochip0 line 8) are on the same line"));
}

TEST_CASE("wiring check: drive mode needs the home_request and home_done lines, not a home line") {
  const std::string drive_mode = "axis.x.mode " + std::to_string(static_cast<int>(homing::HomingMode::drive));
  BackendConfig wiring = drive_wiring();
  wiring.axes[0].home.reset();
  CHECK_FALSE(check_wiring(wiring, drive_settings()));
  BackendConfig no_request = wiring;
  no_request.axes[0].home_request.reset();
  auto problem = check_wiring(no_request, drive_settings());
  REQUIRE(problem);
  CHECK_THAT(*problem, Catch::Contains(drive_mode + " has the drive home itself but [gpiod.axes.X] has no "
                                                    "'home_request' line"));
  BackendConfig no_done = wiring;
  no_done.axes[0].home_done.reset();
  problem = check_wiring(no_done, drive_settings());
  REQUIRE(problem);
  CHECK_THAT(*problem, Catch::Contains(drive_mode + " waits for the drive's home done but [gpiod.axes.X] has no "
                                                    "'home_done' line"));
}
