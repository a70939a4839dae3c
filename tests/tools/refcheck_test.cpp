// homingctl refcheck and the trust in homingctl status, against the real
// homingd restarted on the same database (docs/homing-methods.md "Position
// trust and the reference check").
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "tools_helpers.hpp"

using namespace tools_test;

TEST_CASE("homingctl refcheck after a restart: homes an axis left where it stopped, refuses one moved by hand with the figure") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  {
    Daemon d({.db = db});
    auto r = ctl(d, {"home"});
    SHOW(r);
    REQUIRE(r.code() == 0);
    r = ctl(d, {"status"});
    CHECK(r.out.find("homed_this_power_on") != std::string::npos);
    const auto st = d.stop(SIGTERM, 30s);
    REQUIRE(st);
    REQUIRE(WEXITSTATUS(*st) == 0);
  }
  Daemon d({.db = db});
  auto r = ctl(d, {"status"});
  SHOW(r);
  CHECK(r.out.find("trust") != std::string::npos);
  CHECK(r.out.find("last_stop_clean") != std::string::npos);
  auto j = json_of(ctl(d, {"status", "--json"}));
  CHECK(j["axes"][0]["trust"] == "last_stop_clean");
  CHECK(j["axes"][0]["homed"] == false);

  r = ctl(d, {"refcheck", "x"});
  SHOW(r);
  CHECK(r.code() == 0);
  CHECK(r.out.find("refcheck X: accepted, the switch edge lies ") != std::string::npos);
  CHECK(r.out.find("X is homed at") != std::string::npos);
  j = json_of(ctl(d, {"status", "--json"}));
  CHECK(j["axes"][0]["trust"] == "reference_checked");
  CHECK(j["axes"][0]["homed"] == true);

  // Y's carriage moved 2.5 mm away from its switch while the module was off.
  j = json_of(ctl(d, {"--json", "get", "sim.y.actual_position"}));
  const double y_at = j["sim.y.actual_position"]["value"].get<double>();
  REQUIRE(ctl(d, {"set", fmt::format("sim.y.actual_position={}", y_at + 2.5)}).code() == 0);
  r = ctl(d, {"--json", "refcheck", "y"});
  SHOW(r);
  CHECK(r.code() == 1);
  j = json_of(r);
  CHECK(j["ok"] == false);
  CHECK(j["accepted"] == false);
  CHECK(j["refcheck_error"].get<double>() == Approx(-2.5).margin(0.02));
  CHECK(j["trust"] == "unknown");
  r = ctl(d, {"refcheck", "y"});
  SHOW(r);
  CHECK(r.code() == 1);
  // Said in words (on stderr, as every failure).
  CHECK(r.err.find("refcheck Y refused: reference check refused: axis.y.trust is not") != std::string::npos);
  CHECK(r.err.find("<a>") == std::string::npos);

  r = ctl(d, {"refcheck", "q"});
  CHECK(r.code() == 2);  // not an axis: a usage error, nothing written
}
