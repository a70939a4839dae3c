// The drive's stall output (hard-stop homing) on its own input line: read as
// a level each period, and required by the wiring check for that mode.
#include <catch2/catch.hpp>

#include <string>

#include "backend_fixture.hpp"
#include "homing/settings.hpp"

using homing::Outputs;

namespace {
constexpr std::int64_t kMs = 1'000'000;

const std::string kWithStall = std::string(fixture::kConfig) + "stall = 26\n";

homing::Settings hard_stop_on_x() {
  homing::Settings s;
  s.axes[0].mode = homing::HomingMode::hard_stop;
  return s;
}
}  // namespace

TEST_CASE("the stall line is read as the axis's stall input in the period it changes") {
  fixture::Backend b(fixture::config(kWithStall.c_str()));
  CHECK_FALSE(b.period(Outputs{}, kMs).axes[0].stall);
  b.chip->set_level_silently("X.stall", true);
  const auto in = b.period(Outputs{}, kMs);
  CHECK(in.axes[0].stall);
  CHECK_FALSE(in.axes[1].stall);  // not wired: no stall invented
  b.chip->set_level_silently("X.stall", false);
  CHECK_FALSE(b.period(Outputs{}, kMs).axes[0].stall);
}

TEST_CASE("hard-stop homing without a stall line is refused by the wiring check, with the line named") {
  const auto problem = homing::gpiod::check_wiring(fixture::config(), hard_stop_on_x());
  REQUIRE(problem);
  CHECK_THAT(*problem, Catch::Contains("axis.x.mode 9 homes on the drive's stall output but [gpiod.axes.X] has no 'stall' line"));
  CHECK_FALSE(homing::gpiod::check_wiring(fixture::config(kWithStall.c_str()), hard_stop_on_x()));
}

TEST_CASE("hard-stop homing by following error is refused by the wiring check: no GPIO line carries an encoder") {
  homing::Settings s = hard_stop_on_x();
  s.axes[0].stall_detect = homing::StallDetect::following_error;
  // With or without a stall line: what stall_detect chooses is the encoder.
  for (const auto& config : {fixture::config(), fixture::config(kWithStall.c_str())}) {
    const auto problem = homing::gpiod::check_wiring(config, s);
    REQUIRE(problem);
    CHECK_THAT(*problem, Catch::Contains("axis.x.stall_detect is 1 (following error: the encoder tells the stop) but "
                                         "the GPIO backend reads no encoder"));
    CHECK_THAT(*problem, Catch::Contains("set axis.x.stall_detect = 0"));
  }
  // The backend reports no position: an axis let through would end in encoder_fault.
  fixture::Backend b(fixture::config());
  CHECK_FALSE(b.period(Outputs{}, kMs).axes[0].absolute_valid);
}

TEST_CASE("the absolute modes are refused by the wiring check naming the axis and the methods that need no encoder") {
  for (const homing::HomingMode m : {homing::HomingMode::absolute, homing::HomingMode::absolute_final}) {
    homing::Settings s;
    s.axes[1].mode = m;
    const auto problem = homing::gpiod::check_wiring(fixture::config(), s);
    REQUIRE(problem);
    CHECK_THAT(*problem, Catch::Contains("axis.y.mode " + std::to_string(static_cast<int>(m)) +
                                         " reads an absolute encoder but the GPIO backend reads no encoder"));
    CHECK_THAT(*problem, Catch::Contains("give Y a method without one"));
  }
}

TEST_CASE("a stall line on a line another signal uses is refused before the hardware is touched") {
  const std::string clash = std::string(fixture::kConfig) + "stall = 12\n";  // the index's line
  const auto c = homing::gpiod::parse_config(toml::parse(clash), "test.toml");
  REQUIRE_FALSE(c);
  CHECK_THAT(c.error(), Catch::Contains("same line"));
}
