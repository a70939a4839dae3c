// Switch health over Modbus/TCP with the real homingd and its simulator unit
// (docs/health.md): several latch passes, their spread and sigma, the
// hysteresis and chatter read in their registers, and switch_not_repeatable
// raised by a noisy simulated switch.
#include <catch2/catch.hpp>

#include "daemon.hpp"
#include "homing/alarms.hpp"
#include "homing/modes.hpp"

using namespace e2e;

namespace {

int code(homing::AlarmCode c) { return static_cast<int>(c); }

// X re-approaches its switch 5 times, starting 5 mm from it.
void configure_x(Client& c, int noise_um, int max_spread_um) {
  REQUIRE(c.write("sim.x.actual_position", 5'000) == 0);
  REQUIRE(c.write("sim.x.noise", noise_um) == 0);
  REQUIRE(c.write("sim.x.hysteresis", 80) == 0);
  REQUIRE(c.write("axis.x.mode", static_cast<int>(homing::HomingMode::switch_reapproach)) == 0);
  REQUIRE(c.write("axis.x.latch_passes", 5) == 0);
  REQUIRE(c.write("axis.x.max_latch_spread", max_spread_um) == 0);
}

}  // namespace

TEST_CASE("over Modbus five latch passes publish their count, spread, sigma, the hysteresis and no chatter") {
  Daemon d;
  Client c = Client::tcp(d.port());
  configure_x(c, 5, 1'000);
  REQUIRE(c.write("cmd.home.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("axis.x.homed") == 1 || c.read("status.alarm") == 1; }, 30s, 20ms));
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("axis.x.latch_passes_done") == 5);
  const auto spread = c.read("axis.x.latch_spread");
  const auto sigma = c.read("axis.x.latch_sigma");
  CHECK(spread > 0);       // 5 µm of noise on each edge shows
  CHECK(spread < 100);
  CHECK(sigma <= spread);
  CHECK(c.read("axis.x.hysteresis") >= 70);  // the simulated 80 µm, give or take the noise
  CHECK(c.read("axis.x.hysteresis") <= 90);
  CHECK(c.read("axis.x.chatter_edges") == 0);
}

TEST_CASE("over Modbus a noisy switch raises switch_not_repeatable with the spread as its value") {
  Daemon d;
  Client c = Client::tcp(d.port());
  configure_x(c, 100, 10);
  REQUIRE(c.write("cmd.home.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 1; }, 30s, 20ms));
  CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::switch_not_repeatable));
  CHECK(c.read("axis.x.homed") == 0);
  CHECK(c.read("axis.x.latch_passes_done") == 5);
  CHECK(c.read("axis.x.alarm_value") == c.read("axis.x.latch_spread"));
  CHECK(c.read("axis.x.latch_spread") > 10);
}
