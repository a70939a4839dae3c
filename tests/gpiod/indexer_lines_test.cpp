// The locking indexer's lines on the fake chip: the unlock output follows the
// engine and is off after shutdown, the unlocked input is read every period,
// the [gpiod] table takes both keys, and the wiring check refuses
// axis.<a>.indexer_lock without them.
#include <catch2/catch.hpp>

#include "backend_fixture.hpp"

using homing::Outputs;
using namespace homing::gpiod;

namespace {

constexpr std::int64_t kMs = 1'000'000;

constexpr const char* kIndexerConfig = R"(
[gpiod]
chip = "gpiochip0"

[gpiod.axes.A]
steps_per_unit = 100
step = 23
dir = 24
home = 4
unlock = 6
unlocked = { line = 7, active_low = true, bias = "pull-up" }
)";

homing::Settings indexer_settings() {
  homing::Settings s;
  s.axes[3].mode = homing::HomingMode::switch_release;
  s.axes[3].indexer_lock = true;
  s.axes[3].lock_timeout_ms = 1000;
  return s;
}

}  // namespace

TEST_CASE("config: the [gpiod] table takes an axis's unlock output and unlocked input") {
  const BackendConfig c = fixture::config(kIndexerConfig);
  REQUIRE(c.axes[3].unlock);
  REQUIRE(c.axes[3].unlocked);
  CHECK(c.axes[3].unlock->role == "A.unlock");
  CHECK(c.axes[3].unlocked->role == "A.unlocked");
  CHECK(c.axes[3].unlocked->active_low);
}

TEST_CASE("the unlock line follows the engine's indexer output and is off after shutdown") {
  fixture::Backend b(fixture::config(kIndexerConfig));
  CHECK_FALSE(b.chip->value("A.unlock"));
  Outputs out{};
  out.axes[3].indexer_unlock = true;
  b.period(out, kMs);
  CHECK(b.chip->value("A.unlock"));
  b.period(Outputs{}, kMs);
  CHECK_FALSE(b.chip->value("A.unlock"));
  b.period(out, kMs);
  REQUIRE(b.chip->value("A.unlock"));
  b.io->shutdown();
  CHECK_FALSE(b.chip->value("A.unlock"));
}

TEST_CASE("the unlocked line is read into the axis's indexer_unlocked input every period") {
  fixture::Backend b(fixture::config(kIndexerConfig));
  b.period(Outputs{}, kMs);
  CHECK_FALSE(b.period(Outputs{}, kMs).axes[3].indexer_unlocked);
  b.chip->set_level_silently("A.unlocked", true);
  CHECK(b.period(Outputs{}, kMs).axes[3].indexer_unlocked);
  CHECK_FALSE(b.period(Outputs{}, kMs).axes[0].indexer_unlocked);  // only A's line
  b.chip->set_level_silently("A.unlocked", false);
  CHECK_FALSE(b.period(Outputs{}, kMs).axes[3].indexer_unlocked);
}

TEST_CASE("wiring check: axis.<a>.indexer_lock needs both the unlock and the unlocked line") {
  const BackendConfig wired = fixture::config(kIndexerConfig);
  CHECK_FALSE(check_wiring(wired, indexer_settings()));

  BackendConfig no_unlock = wired;
  no_unlock.axes[3].unlock.reset();
  auto problem = check_wiring(no_unlock, indexer_settings());
  REQUIRE(problem);
  CHECK_THAT(*problem, Catch::Contains("axis.a.indexer_lock is on but [gpiod.axes.A] has no 'unlock' line") &&
                           Catch::Contains("axis.a.indexer_lock = 0"));

  BackendConfig no_unlocked = wired;
  no_unlocked.axes[3].unlocked.reset();
  problem = check_wiring(no_unlocked, indexer_settings());
  REQUIRE(problem);
  CHECK_THAT(*problem, Catch::Contains("[gpiod.axes.A] has no 'unlocked' line"));

  homing::Settings off = indexer_settings();
  off.axes[3].indexer_lock = false;
  CHECK_FALSE(check_wiring(no_unlocked, off));  // without the feature the lines are not needed
}

TEST_CASE("config: the unlock line may not share a line with another signal") {
  const std::string text = std::string(kIndexerConfig) + "\n[gpiod.axes.B]\nunlocked = 6\n";
  auto c = parse_config(toml::parse(text), "test.toml");
  REQUIRE_FALSE(c);
  CHECK_THAT(c.error(), Catch::Contains("same line"));
}
