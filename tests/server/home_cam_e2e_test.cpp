// Home cam with limit-switch reversal on the real homingd over Modbus/TCP:
// X in mode home_cam over the wire finds a cam behind its start after
// reversing at the limit switch, and each of the limit alarms is raised by a
// simulated cause, shown with its code, and reset.
#include <catch2/catch.hpp>

#include "daemon.hpp"
#include "homing/alarms.hpp"
#include "homing/settings.hpp"
#include "homing/sim/config.hpp"

using namespace e2e;
using namespace std::chrono_literals;

namespace {

bool cycle_over(Client& c) { return c.read("status.homing") == 0 && c.read("axis.x.velocity") == 0; }

// X between limit switches at -100 and +100 mm (stops 10 mm beyond), the cam
// at 60..70 mm behind the start at 50 mm (homing negative).
void cam_machine(Client& c) {
  c.set("sim.x.hard_stop_min", -110'000);
  c.set("sim.x.hard_stop_max", 110'000);
  c.set("sim.x.limit_min", -100'000);
  c.set("sim.x.limit_max", 100'000);
  c.set("sim.x.sensor_min", 60'000);
  c.set("sim.x.sensor_max", 70'000);
  c.set("sim.x.actual_position", 50'000);
  c.set("axis.x.limits_fitted", 1);
  c.set("axis.x.mode", static_cast<std::int64_t>(homing::HomingMode::home_cam));
}

void home_x(Client& c) {
  REQUIRE(c.write("cmd.home.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.homing") == 1 || c.read("status.alarm") == 1; }, 5s, 5ms));
  REQUIRE(wait_until([&] { return cycle_over(c); }, 30s, 10ms));
}

std::int64_t code(homing::AlarmCode a) { return static_cast<std::int64_t>(a); }

}  // namespace

TEST_CASE("home cam over Modbus reverses at the limit switch and homes on the cam, and each limit alarm is raised and reset") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  cam_machine(c);
  REQUIRE(c.read("axis.x.mode") == static_cast<std::int64_t>(homing::HomingMode::home_cam));

  home_x(c);
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("axis.x.homed") == 1);
  // The cam's top edge (70 + 0.05 hysteresis) left upward, pull-off 1 mm above it.
  CHECK(std::abs(c.read("sim.x.actual_position") - 71'050) < 30);

  SECTION("no cam between the limit switches: cam_not_found") {
    c.set("sim.x.sensor_min", 200'000);
    c.set("sim.x.sensor_max", 300'000);
    home_x(c);
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::cam_not_found));
    CHECK(c.read("axis.x.alarm_phase") == static_cast<std::int64_t>(homing::Phase::limit_reversal));
  }
  SECTION("both limit switches stuck active: both_limits_active, nothing moves") {
    c.set("sim.x.fault", static_cast<std::int64_t>(homing::sim::Fault::limits_stuck));
    const auto before = c.read("sim.x.actual_position");
    home_x(c);
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::both_limits_active));
    CHECK(c.read("sim.x.actual_position") == before);
  }
  SECTION("the latch runs into the limit switch: limit_in_homing") {
    c.set("sim.x.sensor_min", -95'000);
    c.set("sim.x.sensor_max", -90'000);
    c.set("sim.x.limit_min", -93'000);
    c.set("axis.x.cam_edge", static_cast<std::int64_t>(homing::CamEdge::ahead));
    home_x(c);
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::limit_in_homing));
  }
  SECTION("a jog onto the limit switch: limit_switch, and the reset is taken on the switch") {
    c.set("sim.x.actual_position", 99'000);
    REQUIRE(c.write("cmd.jog_plus.x", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("status.alarm") == 1; }, 10s, 5ms));
    REQUIRE(c.write("cmd.jog_plus.x", 0) == 0);
    REQUIRE(wait_until([&] { return c.read("axis.x.velocity") == 0; }, 5s, 5ms));
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::limit_switch));
    CHECK(c.read("sim.x.limit_max_active") == 1);
    CHECK(c.read("sim.x.actual_position") < 110'000);
  }
  // Reset once the cause is gone, then home again.
  c.set("sim.x.fault", 0);
  c.set("sim.x.sensor_min", 60'000);
  c.set("sim.x.sensor_max", 70'000);
  c.set("sim.x.limit_min", -100'000);
  c.set("axis.x.cam_edge", 0);
  c.set("sim.x.actual_position", 50'000);
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 0; }, 2s));
  CHECK(c.read("axis.x.alarm") == 0);
  home_x(c);
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("axis.x.homed") == 1);
}
