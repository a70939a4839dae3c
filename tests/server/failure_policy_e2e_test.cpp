// The failure policy over Modbus/TCP on the real homingd and its simulator
// unit: global.failure_policy (holding register 61) written over the wire
// decides what the default sequence (Z, then X + Y) does when X cannot find
// its sensor in step 2, the simulator's carriages showing where each axis
// ended; a value outside the list is refused and changes nothing.
#include <catch2/catch.hpp>

#include <cstdlib>

#include "daemon.hpp"
#include "homing/alarms.hpp"
#include "homing/phases.hpp"
#include "homing/settings.hpp"

using namespace e2e;
using namespace std::chrono_literals;

namespace {

std::int64_t raw(homing::FailurePolicy p) { return static_cast<std::int64_t>(p); }

// X's seek ends 50 mm into its 100 mm way to the sensor: sensor_not_found
// while Y is still seeking its own.
void x_out_of_reach(Client& c) { c.set("axis.x.max_seek_travel", 50'000); }

struct Positions {
  std::int64_t x, y, z;
};
Positions carriages(Client& c) {
  return {c.read("sim.x.actual_position"), c.read("sim.y.actual_position"), c.read("sim.z.actual_position")};
}

// Starts home-all and waits for the cycle and the motion to end; whether
// Y was seen going back (phase return_to_start) meanwhile.
bool home_all(Client& c) {
  bool returned = false;
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.homing") == 1 || c.read("status.alarm") == 1; }, 5s, 5ms));
  REQUIRE(wait_until(
      [&] {
        returned = returned || c.read("axis.y.phase") == static_cast<std::int64_t>(homing::Phase::return_to_start);
        return c.read("status.homing") == 0 && c.read("axis.x.velocity") == 0 && c.read("axis.y.velocity") == 0 &&
               c.read("axis.z.velocity") == 0;
      },
      30s, 5ms));
  return returned;
}

}  // namespace

TEST_CASE("global.failure_policy written over Modbus decides what home-all does when X fails") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  CHECK(c.read("global.failure_policy") == raw(homing::FailurePolicy::stop_all));  // a new module's
  x_out_of_reach(c);
  const Positions start = carriages(c);
  const auto cycles = c.read("status.homing_cycles");

  SECTION("stop_all: every axis stops where X's alarm found it") {
    CHECK_FALSE(home_all(c));
    CHECK(c.read("axis.x.alarm") == static_cast<std::int64_t>(homing::AlarmCode::sensor_not_found));
    CHECK(c.read("status.alarm_axis") == 1);
    CHECK(c.read("axis.y.homed") == 0);
    const Positions end = carriages(c);
    CHECK(end.y < start.y - 40'000);  // on its way to the sensor when it stopped
    CHECK(end.y > 10'000);
  }
  SECTION("finish_independent: Y finishes its homing beside the failed X") {
    c.set("global.failure_policy", raw(homing::FailurePolicy::finish_independent));
    CHECK(c.read("global.failure_policy") == raw(homing::FailurePolicy::finish_independent));
    CHECK_FALSE(home_all(c));
    CHECK(c.read("axis.x.alarm") == static_cast<std::int64_t>(homing::AlarmCode::sensor_not_found));
    CHECK(c.read("status.alarm_axis") == 1);
    CHECK(c.read("axis.y.alarm") == 0);
    CHECK(c.read("axis.y.homed") == 1);
    CHECK(c.read("axis.y.phase") == static_cast<std::int64_t>(homing::Phase::done));
    CHECK(c.read("axis.y.position") == c.read("axis.y.home_position"));
    CHECK(c.read("status.state") == static_cast<std::int64_t>(homing::MachineState::alarm));
  }
  SECTION("return_to_start: Y and Z go back to where the cycle found them; X, whose seek ran out, stays") {
    c.set("global.failure_policy", raw(homing::FailurePolicy::return_to_start));
    CHECK(home_all(c));
    CHECK(c.read("axis.x.alarm") == static_cast<std::int64_t>(homing::AlarmCode::sensor_not_found));
    CHECK(c.read("status.alarm_axis") == 1);
    const Positions end = carriages(c);
    CHECK(std::llabs(end.x - (start.x - 50'000)) < 1'000);  // where its 50 mm seek ended
    CHECK(std::llabs(end.y - start.y) <= 1);
    CHECK(std::llabs(end.z - start.z) <= 1);
    CHECK(c.read("axis.z.homed") == 0);
  }
  SECTION("a value that names no policy is refused and changes nothing") {
    CHECK(c.write("global.failure_policy", 3) == 3);
    CHECK(c.read("global.failure_policy") == raw(homing::FailurePolicy::stop_all));
    return;
  }
  CHECK(c.read("status.homing_cycles") == cycles);
  // Reset, give X its reach back: the machine homes.
  c.set("axis.x.max_seek_travel", 500'000);
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 0; }, 2s));
  home_all(c);
  CHECK(c.read("status.state") == static_cast<std::int64_t>(homing::MachineState::homed));
}
