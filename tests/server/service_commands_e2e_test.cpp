// Service commands over Modbus/TCP on the real homingd (simulator): cmd.unhome.<a>
// forgets an axis's reference without moving it, logged with the client; with
// global.single_axis_homing = 0 a single-axis home is refused with its own
// command result and only home-all homes.
#include <catch2/catch.hpp>

#include "daemon.hpp"
#include "homing/status.hpp"

using namespace e2e;

namespace {
template <class E>
std::int64_t v(E e) {
  return static_cast<std::int64_t>(e);
}
bool homed_all(Client& c) { return c.read("status.state") == v(homing::MachineState::homed); }
}  // namespace

TEST_CASE("over Modbus: cmd.unhome.<a> unhomes the axis without moving it and the log names the client") {
  Daemon d;
  Client c = Client::tcp(d.port());
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return homed_all(c) || c.read("status.alarm") != 0; }, 30s));
  REQUIRE(c.read("axis.x.homed") == 1);
  const std::int64_t x_at = c.read("sim.x.actual_position");
  const std::int64_t count = c.read("status.command_count");
  REQUIRE(c.write("cmd.unhome.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") != count; }, 2s));
  CHECK(c.read("status.last_command_result") == v(homing::CommandResult::accepted));
  CHECK(c.read("axis.x.homed") == 0);
  CHECK(c.read("axis.y.homed") == 1);
  CHECK(c.read("sim.x.actual_position") == x_at);
  CHECK(c.read("cmd.unhome.x") == 0);
  CHECK(d.log().find("unhome.x") != std::string::npos);
}

TEST_CASE("over Modbus: with global.single_axis_homing 0 a single-axis home is refused_home_all_only and home-all homes") {
  Daemon d;
  Client c = Client::tcp(d.port());
  CHECK(c.read("global.single_axis_homing") == 1);
  c.set("global.single_axis_homing", 0);
  const std::int64_t x_at = c.read("sim.x.actual_position");
  std::int64_t count = c.read("status.command_count");
  REQUIRE(c.write("cmd.home.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") != count; }, 2s));
  CHECK(c.read("status.last_command_result") == v(homing::CommandResult::refused_home_all_only));
  count = c.read("status.command_count");
  REQUIRE(c.write("cmd.home_axes", 0b011) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") != count; }, 2s));
  CHECK(c.read("status.last_command_result") == v(homing::CommandResult::refused_home_all_only));
  CHECK(c.read("status.homing") == 0);
  CHECK(c.read("sim.x.actual_position") == x_at);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return homed_all(c) || c.read("status.alarm") != 0; }, 30s));
  CHECK(homed_all(c));
}
