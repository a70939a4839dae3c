// `homingctl home x y`: the named axes in one cycle through cmd.home_axes,
// against the real homingd; the register's refusals on the wire.
#include <catch2/catch.hpp>

#include "tools_helpers.hpp"

using namespace tools_test;

TEST_CASE("homingctl home x y homes X and Y in one cycle and leaves Z alone") {
  Daemon d;
  Client c = Client::tcp(d.port());
  REQUIRE(ctl(d, {"set", "axis.x.home_position=-5", "axis.y.home_position=-7"}).code() == 0);
  const auto z0 = c.read("sim.z.actual_position");
  auto r = ctl(d, {"home", "x", "y"});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
    CHECK(r.out.find("home X Y: done, X = -5.000 mm, Y = -7.000 mm, Z = ") != std::string::npos);
    CHECK(r.out.find("(not homed)") != std::string::npos);  // Z
  }
  CHECK(c.read("status.homing_cycles") == 1);
  CHECK(c.read("axis.x.homed") == 1);
  CHECK(c.read("axis.y.homed") == 1);
  CHECK(c.read("axis.z.homed") == 0);
  CHECK(c.read("sim.z.actual_position") == z0);
  CHECK(c.read("cmd.home_axes") == 0);

  // One axis still works, through the same register.
  auto j = json_of(ctl(d, {"--json", "home", "z"}));
  CHECK(j["ok"] == true);
  CHECK(j["command"] == "home Z");
  CHECK(c.read("status.homing_cycles") == 2);
  CHECK(c.read("status.state") == static_cast<int>(homing::MachineState::homed));
}

TEST_CASE("homingctl home names a word that is not an axis as a usage error, and refuses a disabled axis") {
  Daemon d;
  Client c = Client::tcp(d.port());
  auto r = ctl(d, {"home", "x", "q"});
  {
    SHOW(r);
    CHECK(r.code() == 2);
    CHECK(r.err.find("'q' is not an axis") != std::string::npos);
  }
  r = ctl(d, {"home", "x", "a"});  // A is disabled by default
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("A is disabled (axis.a.mode = disabled)") != std::string::npos);
  }
  CHECK(c.read("status.command_count") == 0);
  CHECK(c.read("status.homing") == 0);
}

TEST_CASE("cmd.home_axes refuses on the wire what it cannot start, and changes nothing") {
  Daemon d;
  Client c = Client::tcp(d.port());
  CHECK(c.write("cmd.home_axes", 0) == 3);       // names no axis
  CHECK(c.write("cmd.home_axes", 0b1001) == 3);  // X and the disabled A
  CHECK(c.write("cmd.home_axes", 64) == 3);      // no axis G
  CHECK(c.read("status.command_count") == 0);

  // While a cycle runs: 06, and homingctl says why.
  for (const char* a : {"x", "y", "z"}) c.set(std::string("sim.") + a + ".actual_position", um(400));
  REQUIRE(ctl(d, {"home", "--no-wait"}).code() == 0);
  REQUIRE(c.read("status.homing") == 1);
  const auto count = c.read("status.command_count");
  CHECK(c.write("cmd.home_axes", 0b001) == 6);
  auto r = ctl(d, {"home", "x"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("home X refused: another homing cycle or motion is running") != std::string::npos);
  }
  CHECK(c.read("status.command_count") == count);
  CHECK(c.read("status.homing") == 1);

  // With an alarm latched: 04, and homingctl says which.
  REQUIRE(ctl(d, {"abort"}).code() == 0);
  REQUIRE(c.read("status.alarm") == 1);
  CHECK(c.write("cmd.home_axes", 0b001) == 4);
  r = ctl(d, {"home", "x", "y"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("home X Y refused: an alarm is latched: reset first") != std::string::npos);
  }
  CHECK(c.read("status.homing") == 0);
}

TEST_CASE("homingctl unhome forgets an axis's reference and its gantry partner's without moving anything") {
  Daemon d;
  Client c = Client::tcp(d.port());
  REQUIRE(ctl(d, {"set", "axis.z.mode=disabled", "sequence.step1=3", "sequence.step2=0", "axis.y.slave_of=1"}).code() == 0);
  REQUIRE(ctl(d, {"home"}).code() == 0);
  REQUIRE(c.read("axis.x.homed") == 1);
  REQUIRE(c.read("axis.y.homed") == 1);
  const auto x0 = c.read("sim.x.actual_position"), y0 = c.read("sim.y.actual_position");
  auto r = ctl(d, {"unhome", "y"});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
    CHECK(r.out.find("unhome Y: done; Y and its gantry partner X no longer homed, nothing moved; home the pair again") !=
          std::string::npos);
  }
  CHECK(c.read("axis.x.homed") == 0);
  CHECK(c.read("axis.y.homed") == 0);
  CHECK(c.read("sim.x.actual_position") == x0);
  CHECK(c.read("sim.y.actual_position") == y0);
  CHECK(c.read("status.last_command_result") == static_cast<int>(homing::CommandResult::accepted));
  r = ctl(d, {"unhome", "q"});
  {
    SHOW(r);
    CHECK(r.code() == 2);
    CHECK(r.err.find("'q' is not an axis") != std::string::npos);
  }
}
