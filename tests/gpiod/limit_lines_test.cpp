// The limit switches' lines on the fake chip: the [gpiod] table takes
// limit_min and limit_max, both are read as levels every period, and the
// wiring check refuses axis.<a>.limits_fitted (and so home_cam) without both.
#include <catch2/catch.hpp>

#include "backend_fixture.hpp"

using homing::Outputs;
using namespace homing::gpiod;

namespace {

constexpr std::int64_t kMs = 1'000'000;

constexpr const char* kLimitConfig = R"(
[gpiod]
chip = "gpiochip0"

[gpiod.axes.X]
steps_per_unit = 100
step = 23
dir = 24
home = 4
limit_min = 6
limit_max = { line = 7, active_low = true, bias = "pull-up" }
)";

homing::Settings cam_settings() {
  homing::Settings s;
  s.axes[0].mode = homing::HomingMode::home_cam;
  s.axes[0].limits_fitted = true;
  return s;
}

}  // namespace

TEST_CASE("config: the [gpiod] table takes an axis's limit_min and limit_max inputs") {
  const BackendConfig c = fixture::config(kLimitConfig);
  REQUIRE(c.axes[0].limit_min);
  REQUIRE(c.axes[0].limit_max);
  CHECK(c.axes[0].limit_min->role == "X.limit_min");
  CHECK(c.axes[0].limit_max->role == "X.limit_max");
  CHECK(c.axes[0].limit_max->active_low);
}

TEST_CASE("the limit lines are read into the axis's limit levels every period") {
  fixture::Backend b(fixture::config(kLimitConfig));
  b.period(Outputs{}, kMs);
  CHECK_FALSE(b.period(Outputs{}, kMs).axes[0].limit_min_level);
  b.chip->set_level_silently("X.limit_min", true);
  const auto in = b.period(Outputs{}, kMs);
  CHECK(in.axes[0].limit_min_level);
  CHECK_FALSE(in.axes[1].limit_min_level);  // only X's line
  b.chip->set_level_silently("X.limit_min", false);
  CHECK_FALSE(b.period(Outputs{}, kMs).axes[0].limit_min_level);
  b.chip->set_level_silently("X.limit_max", true);
  CHECK(b.period(Outputs{}, kMs).axes[0].limit_max_level);
}

TEST_CASE("wiring check: limits_fitted and home_cam need both limit lines") {
  const BackendConfig wired = fixture::config(kLimitConfig);
  CHECK_FALSE(check_wiring(wired, cam_settings()));

  BackendConfig no_min = wired;
  no_min.axes[0].limit_min.reset();
  auto problem = check_wiring(no_min, cam_settings());
  REQUIRE(problem);
  CHECK_THAT(*problem, Catch::Contains("axis.x.limits_fitted is on but [gpiod.axes.X] has no 'limit_min' line"));

  BackendConfig no_max = wired;
  no_max.axes[0].limit_max.reset();
  problem = check_wiring(no_max, cam_settings());
  REQUIRE(problem);
  CHECK_THAT(*problem, Catch::Contains("no 'limit_max' line"));

  homing::Settings off;
  off.axes[0].mode = homing::HomingMode::switch_release;
  CHECK_FALSE(check_wiring(no_max, off));  // without limit switches the lines are not needed
}
