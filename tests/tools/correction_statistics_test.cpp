// The home-correction statistics over a restart of the real homingd on the
// same database: only cycles that started homed count, and the history says
// which cycles are left out and why.
#include <catch2/catch.hpp>

#include "tools_helpers.hpp"

using namespace tools_test;

namespace {

nlohmann::json history(const std::string& db) {
  return json_of(run_program({HOMINGCTL_PATH, "history", "--json", "--db", db, "--corrections", "10"}, 30s));
}

// Two home-alls in one run of the daemon, recorded in its history.
void home_twice(const std::string& db, std::size_t runs_after) {
  Daemon d({.db = db, .time_scale = 10});
  for (int i = 0; i < 2; ++i) {
    auto r = ctl(d, {"home"});
    SHOW(r);
    REQUIRE(r.code() == 0);
  }
  // The daemon records a run just after it ends.
  REQUIRE(wait_until([&] { return history(db)["runs"].size() == runs_after; }, 5s));
  Client c = Client::tcp(d.port());
  REQUIRE(wait_until([&] { return std::abs(c.read("axis.x.correction_mean")) < 50; }, 5s));  // µm
  CHECK(std::abs(c.read("axis.x.correction_spread")) < 50);
}

}  // namespace

TEST_CASE("home-correction statistics over a daemon restart count only cycles that started homed") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  home_twice(db, 2);
  home_twice(db, 4);  // the same database: its first cycle starts unhomed again

  auto j = history(db);
  REQUIRE(j["runs"].size() == 4);  // newest first: #4 #3 #2 #1
  for (const char* axis : {"x", "y", "z"}) {
    INFO(axis);
    CHECK(j["runs"][3]["axes"][axis]["excluded"] == "not homed before the cycle");  // #1: after a start
    CHECK(j["runs"][3]["axes"][axis]["correction"].is_null());
    CHECK(j["runs"][2]["axes"][axis]["excluded"].is_null());
    CHECK(j["runs"][1]["axes"][axis]["excluded"] == "not homed before the cycle");  // #3: after the restart
    CHECK(j["runs"][0]["axes"][axis]["excluded"].is_null());
    CHECK(std::abs(j["runs"][0]["axes"][axis]["correction"].get<double>()) < 0.05);
  }
  REQUIRE(j["corrections"].size() == 3);
  for (const auto& axis : j["corrections"]) {
    INFO(axis.dump());
    CHECK(axis["runs"] == 2);
    CHECK(std::abs(axis["mean"].get<double>()) < 0.05);
    CHECK(axis["spread"].get<double>() < 0.05);
  }
  REQUIRE(j["excluded"].size() == 6);  // X Y Z of #1 and #3
  CHECK(j["excluded"][0]["run"] == 3);
  CHECK(j["excluded"][0]["reason"] == "not homed before the cycle");

  auto r = run_program({HOMINGCTL_PATH, "history", "--db", db, "--corrections", "10"}, 30s);
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("X Y Z excluded: not homed before the cycle") != std::string::npos);
  CHECK(r.out.find("  run #1:  X Y Z excluded: not homed before the cycle\n") != std::string::npos);
  CHECK(r.out.find("  run #3:  X Y Z excluded: not homed before the cycle\n") != std::string::npos);
  CHECK(r.out.find("\n  X     2 ") != std::string::npos);
}

TEST_CASE("a new home position unhomes the axis, so the next cycle's correction of it is left out") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  Daemon d({.db = db, .time_scale = 10});
  REQUIRE(ctl(d, {"home"}).code() == 0);
  Client c = Client::tcp(d.port());
  REQUIRE(c.read("axis.x.homed") == 1);
  REQUIRE(ctl(d, {"set", "axis.x.home_position=5"}).code() == 0);
  // X's coordinates were measured for the old home position: no longer homed. Y keeps its.
  CHECK(wait_until([&] { return c.read("axis.x.homed") == 0; }, 5s));
  CHECK(c.read("axis.y.homed") == 1);
  auto r = ctl(d, {"home"});
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(c.read("axis.x.position") == 5000);  // µm: the new coordinate
  REQUIRE(wait_until([&] { return history(db)["runs"].size() == 2; }, 5s));
  const auto j = history(db);
  CHECK(j["runs"][0]["axes"]["x"]["excluded"] == "not homed before the cycle");
  CHECK(j["runs"][0]["axes"]["y"]["excluded"].is_null());
}
