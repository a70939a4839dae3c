// The health trend end to end (docs/health.md "Trends"): the real homingd and
// its simulator unit over Modbus/TCP, cycles homed one after another while a
// simulated fault grows, the warning register, the daemon's log line,
// homingctl health and the history the daemon kept.
#include <catch2/catch.hpp>

#include <regex>

#include "homing/health.hpp"
#include "homing/modes.hpp"
#include "tools_helpers.hpp"

using namespace tools_test;

namespace {

int warning(homing::HealthWarning w) { return static_cast<int>(w); }

// One homing cycle of the axes named (a coil), to the end; the machine must end homed.
void home(Client& c, std::string_view coil) {
  const auto cycles = c.read("status.homing_cycles");
  REQUIRE(c.write(coil, 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.homing_cycles") > cycles || c.read("status.alarm") == 1; }, 30s,
                     10ms));
  REQUIRE(c.read("status.alarm") == 0);
  // The monitor judges the trend once it saw the cycle end.
  std::this_thread::sleep_for(100ms);
}

std::size_t lines_with(const std::string& log, const std::string& what) { return count_of(log, what); }

}  // namespace

TEST_CASE("over Modbus a switch whose hysteresis grows raises hysteresis_growing: register, one log line, "
          "homingctl health, kept over a restart") {
  TempDir dir;
  const std::string db = dir.file("settings.db");
  {
    Daemon d({.db = db});
    Client c = Client::tcp(d.port());
    c.set("axis.x.mode", static_cast<int>(homing::HomingMode::switch_reapproach));
    c.set("sim.x.actual_position", um(5));
    c.set("sim.x.noise", 0);
    c.set("global.trend_cycles", 4);
    c.set("global.trend_growth_pct", 50);
    REQUIRE(c.read_mm("global.trend_min_change") == Approx(0.010));

    // Four cycles of a steady switch (the first three are fewer than the trend compares).
    c.set("sim.x.hysteresis", 50);
    for (int i = 0; i < 4; ++i) {
      home(c, "cmd.home.x");
      CHECK(c.read("axis.x.health_warning") == warning(homing::HealthWarning::none));
    }
    // It wears: 0.05 -> 0.10 mm. The last four cycles: the first measured 0.05, the newest 0.10.
    c.set("sim.x.hysteresis", 100);
    home(c, "cmd.home.x");
    CHECK(c.read("axis.x.hysteresis") == Approx(100).margin(3));
    CHECK(c.read("axis.x.health_warning") == warning(homing::HealthWarning::hysteresis_growing));
    // A warning, not an alarm: the axis stays homed and moves.
    CHECK(c.read("axis.x.homed") == 1);
    CHECK(c.read("status.alarm") == 0);
    CHECK(c.read("axis.y.health_warning") == warning(homing::HealthWarning::none));
    // It grows on: the same warning, still logged once.
    c.set("sim.x.hysteresis", 150);
    home(c, "cmd.home.x");
    CHECK(c.read("axis.x.health_warning") == warning(homing::HealthWarning::hysteresis_growing));
    const std::string log = d.log();
    INFO(log);
    CHECK(lines_with(log, "health warning hysteresis_growing on X") == 1);
    CHECK(std::regex_search(log, std::regex("health warning hysteresis_growing on X \\(not an alarm: the axis stays "
                                            "homed\\): X hysteresis 0\\.(09[7-9]|10[0-3]) mm, was 0\\.0(4[7-9]|5[0-3]) "
                                            "mm over the last 4 cycles: the switch is wearing; check its mounting "
                                            "and plunger")));

    auto r = ctl(d, {"health"});
    SHOW(r);
    REQUIRE(r.code() == 0);
    CHECK(r.out.find("hysteresis_growing: the switch's hysteresis grew over the last cycles") != std::string::npos);
    CHECK(r.out.find("homingctl history --trend x") != std::string::npos);
    auto j = json_of(ctl(d, {"--json", "health"}));
    CHECK(j["x"]["health_warning"] == "hysteresis_growing");
    CHECK(j["x"]["warnings"].size() == 1);
    CHECK(j["x"]["gantry_skew"].is_null());  // X is no gantry slave

    // The history kept every cycle's figures.
    r = ctl_plain({"history", "--db", db, "--json", "--trend", "x"});
    SHOW(r);
    j = json_of(r);
    REQUIRE(j["cycles"].size() == 6);
    CHECK(j["cycles"][0]["hysteresis"].get<double>() == Approx(0.05).margin(0.003));
    CHECK(j["cycles"][5]["hysteresis"].get<double>() == Approx(0.15).margin(0.003));

    // The switch is replaced: four good cycles later the warning clears, and the log says so once.
    c.set("sim.x.hysteresis", 50);
    for (int i = 0; i < 4; ++i) home(c, "cmd.home.x");
    CHECK(c.read("axis.x.health_warning") == warning(homing::HealthWarning::none));
    CHECK(lines_with(d.log(), "health warning hysteresis_growing on X cleared") == 1);
    c.set("sim.x.hysteresis", 150);
    home(c, "cmd.home.x");
    REQUIRE(c.read("axis.x.health_warning") == warning(homing::HealthWarning::hysteresis_growing));
  }
  // A restart does not hide it: the history still says so.
  Daemon d({.db = db});
  Client c = Client::tcp(d.port());
  REQUIRE(wait_until([&] { return c.read("axis.x.health_warning") == warning(homing::HealthWarning::hysteresis_growing); },
                     5s, 20ms));
  CHECK(d.log().find("health warning hysteresis_growing on X") != std::string::npos);
}

TEST_CASE("over Modbus a gantry publishes its skew on the slave, and a slave sensor that moved raises "
          "gantry_skew_changed for one cycle") {
  Daemon d;
  Client c = Client::tcp(d.port());
  // Y as the software-slaved second motor of X; only X and Y home.
  c.set("axis.z.mode", 0);
  c.set("sequence.step1", 0b011);
  c.set("sequence.step2", 0);
  c.set("axis.y.slave_mode", 0);
  c.set("axis.y.slave_of", 1);
  c.set("sim.x.noise", 0);
  c.set("sim.y.noise", 0);
  c.set("global.trend_cycles", 3);
  REQUIRE(c.read_mm("axis.y.max_skew_change") == Approx(0.1));
  // The slave's sensor sits 0.4 mm further out; both carriages start at 100 mm.
  c.set("sim.y.sensor_max", um(0.4));
  REQUIRE(c.read("sim.x.actual_position") == c.read("sim.y.actual_position"));

  home(c, "cmd.home_all");
  CHECK(c.read_mm("axis.y.gantry_skew") == Approx(0.4).margin(0.003));  // published on the slave
  CHECK(c.read("axis.x.gantry_skew") == 0);
  // Squared on its sensors, the pair stands square with them from then on.
  for (int i = 0; i < 3; ++i) {
    home(c, "cmd.home_all");
    CHECK(c.read_mm("axis.y.gantry_skew") == Approx(0).margin(0.003));
    CHECK(c.read("axis.y.health_warning") == warning(homing::HealthWarning::none));
  }
  // The first cycle found the carriages where they were left: published, not kept for the trend.
  auto j = json_of(ctl_plain({"history", "--db", d.db(), "--json", "--trend", "y"}));
  REQUIRE(j["cycles"].size() == 4);
  CHECK(j["cycles"][0]["gantry_skew"].is_null());
  CHECK(j["cycles"][1]["gantry_skew"].get<double>() == Approx(0).margin(0.003));

  // The slave's sensor slips 0.4 mm back toward the cam.
  c.set("sim.y.sensor_max", 0);
  home(c, "cmd.home_all");
  CHECK(c.read_mm("axis.y.gantry_skew") == Approx(-0.4).margin(0.003));
  CHECK(c.read("axis.y.health_warning") == warning(homing::HealthWarning::gantry_skew_changed));
  CHECK(c.read("axis.x.health_warning") == warning(homing::HealthWarning::none));
  CHECK(c.read("axis.y.homed") == 1);
  std::string log = d.log();
  {
    INFO(log);
    CHECK(std::regex_search(log, std::regex("health warning gantry_skew_changed on Y \\(not an alarm: the axis stays "
                                            "homed\\): X/Y skew -0\\.(39[7-9]|40[0-3]) mm, was 0\\.00[0-3] mm over "
                                            "the last 3 cycles: check the slave's coupling and sensor")));
  }
  auto r = ctl(d, {"health"});
  SHOW(r);
  CHECK(r.out.find("gantry_skew_changed") != std::string::npos);
  CHECK(std::regex_search(r.out, std::regex("\nY .* -0\\.(39[7-9]|40[0-3])[0-9]  gantry_skew_changed")));
  // Squared on the sensor where it now sits, the next cycle is square again: the warning goes.
  home(c, "cmd.home_all");
  CHECK(c.read("axis.y.health_warning") == warning(homing::HealthWarning::none));
  log = d.log();
  CHECK(count_of(log, "health warning gantry_skew_changed on Y") == 2);  // raised, then cleared
  CHECK(log.find("health warning gantry_skew_changed on Y cleared") != std::string::npos);
}
