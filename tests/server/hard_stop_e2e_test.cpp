// Hard-stop homing on the real homingd over Modbus/TCP (libmodbus): X set to
// mode hard_stop over the wire homes against the simulator's mechanical stop,
// and each of its alarms is raised by a simulated fault, shown with its code,
// and reset.
#include <catch2/catch.hpp>

#include "daemon.hpp"
#include "homing/alarms.hpp"
#include "homing/settings.hpp"
#include "homing/sim/config.hpp"

using namespace e2e;
using namespace std::chrono_literals;

namespace {

bool cycle_over(Client& c) { return c.read("status.homing") == 0 && c.read("axis.x.velocity") == 0; }

// X alone: no cam anywhere (max below min), the carriage at 3 mm, its stop at -5 mm.
void hard_stop_machine(Client& c) {
  c.set("sim.x.sensor_min", 1'000'000);
  c.set("sim.x.sensor_max", 0);
  c.set("sim.x.hard_stop_min", -5'000);
  c.set("sim.x.actual_position", 3'000);
  c.set("axis.x.mode", static_cast<std::int64_t>(homing::HomingMode::hard_stop));
}

void home_x(Client& c) {
  REQUIRE(c.write("cmd.home.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.homing") == 1 || c.read("status.alarm") == 1; }, 5s, 5ms));
  REQUIRE(wait_until([&] { return cycle_over(c); }, 20s, 10ms));
}

std::int64_t code(homing::AlarmCode a) { return static_cast<std::int64_t>(a); }

}  // namespace

TEST_CASE("hard-stop homing over Modbus homes against the stop, and each of its alarms is raised and reset") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  hard_stop_machine(c);
  REQUIRE(c.read("axis.x.mode") == static_cast<std::int64_t>(homing::HomingMode::hard_stop));

  home_x(c);
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("axis.x.homed") == 1);
  CHECK(c.read("axis.x.position") == 0);              // home_position
  CHECK(c.read("sim.x.actual_position") == -4'000);   // pull_off (1 mm) above the stop
  CHECK(c.read("axis.x.phase") == static_cast<std::int64_t>(homing::Phase::done));

  SECTION("a stall output that never turns on: stop_not_found within max_seek_travel") {
    c.set("axis.x.max_seek_travel", 3'000);
    c.set("sim.x.fault", static_cast<std::int64_t>(homing::sim::Fault::stall_dead));
    home_x(c);
    CHECK(c.read("status.alarm") == 1);
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::stop_not_found));
    CHECK(c.read("axis.x.alarm_phase") == static_cast<std::int64_t>(homing::Phase::push_to_stop));
    CHECK(c.read("sim.x.actual_position") == -5'000);  // at the stop, 2 mm of steps lost against it
  }
  SECTION("no stall within stall_timeout_ms: stall_timeout") {
    c.set("sim.x.actual_position", 3'000);
    c.set("axis.x.stall_timeout_ms", 500);  // 0.5 s at 100 mm/min: 0.83 mm of the 8 mm
    home_x(c);
    CHECK(c.read("status.alarm") == 1);
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::stall_timeout));
    CHECK(c.read("sim.x.actual_position") > 1'000);
  }
  SECTION("a stall output on before the push: stall_at_start, and nothing moves") {
    c.set("sim.x.fault", static_cast<std::int64_t>(homing::sim::Fault::stall_stuck));
    const auto before = c.read("sim.x.actual_position");
    home_x(c);
    CHECK(c.read("status.alarm") == 1);
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::stall_at_start));
    CHECK(c.read("sim.x.actual_position") == before);
  }
  // Reset once the cause is gone, then home again.
  c.set("sim.x.fault", 0);
  c.set("axis.x.stall_timeout_ms", 30'000);
  c.set("axis.x.max_seek_travel", 500'000);
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 0; }, 2s));
  CHECK(c.read("axis.x.alarm") == 0);
  home_x(c);
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("axis.x.homed") == 1);
  CHECK(c.read("sim.x.actual_position") == -4'000);
}
