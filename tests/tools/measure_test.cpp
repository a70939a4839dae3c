// homingctl measure against the real homingd and its simulator
// (docs/homing-methods.md "Commissioning measurement"): prints the usable
// travel and the settings that fit it, writes them only with --apply
// (through the settings path: checked, audited), and names what refuses it.
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "tools_helpers.hpp"

using namespace tools_test;

namespace {
// X between limit switches at -3 and 150 mm, homing on its switch at 0.
void fit_limit_switches(const Daemon& d) {
  REQUIRE(ctl(d, {"set", "sim.x.limit_min=-3", "sim.x.limit_max=150", "sim.x.hard_stop_max=155"}).code() == 0);
  REQUIRE(ctl(d, {"set", "axis.x.limits_fitted=1", "axis.x.latch_feedrate=300"}).code() == 0);
}
double setting(const Daemon& d, const std::string& name) {
  const auto j = json_of(ctl(d, {"--json", "get", name}));
  return j[name]["value"].get<double>();
}
}  // namespace

TEST_CASE("homingctl measure prints the travel and the settings that fit, and writes them only with --apply") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  Daemon d({.db = db});
  fit_limit_switches(d);
  const double soft_max = setting(d, "axis.x.soft_limit_max");
  const double seek = setting(d, "axis.x.max_seek_travel");

  auto r = ctl(d, {"measure", "x"});
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("measure X: usable travel ") != std::string::npos);
  CHECK(r.out.find("axis.x.soft_limit_max = ") != std::string::npos);
  CHECK(r.out.find("axis.x.max_seek_travel = ") != std::string::npos);
  CHECK(r.out.find("nothing written: homingctl measure x --apply writes these") != std::string::npos);
  CHECK(setting(d, "axis.x.soft_limit_max") == soft_max);
  CHECK(setting(d, "axis.x.max_seek_travel") == seek);

  r = ctl(d, {"--json", "measure", "x", "--apply"});
  SHOW(r);
  REQUIRE(r.code() == 0);
  const auto j = json_of(r);
  CHECK(j["applied"] == true);
  const double travel = j["measured_travel"].get<double>();
  CHECK(travel == Approx(149).margin(1));  // from its home rest at about 1 mm to the switch at 150 mm
  CHECK(setting(d, "axis.x.soft_limit_min") == Approx(j["soft_limit_min"].get<double>()).margin(0.001));
  CHECK(setting(d, "axis.x.soft_limit_max") == Approx(j["soft_limit_max"].get<double>()).margin(0.001));
  CHECK(setting(d, "axis.x.max_seek_travel") == Approx(j["max_seek_travel"].get<double>()).margin(0.001));
  CHECK(setting(d, "axis.x.max_seek_travel") < seek);
  // Written through the settings path: the settings changes recorded name them.
  r = run_program({HOMINGCTL_PATH, "history", "--db", db, "--changes", "50"}, 30s);
  SHOW(r);
  CHECK(r.code() == 0);
  CHECK(r.out.find("axis.x.max_seek_travel") != std::string::npos);
  CHECK(r.out.find("axis.x.soft_limit_max") != std::string::npos);
}

TEST_CASE("homingctl measure names what refuses it, with a non-zero exit code, and moves nothing") {
  Daemon d;
  auto r = ctl(d, {"measure", "y"});  // Y: a switch method, no limit switches
  SHOW(r);
  CHECK(r.code() == 1);
  CHECK(r.err.find("measure Y refused: measurement refused: it needs both a homing method that homes at one end") !=
        std::string::npos);
  // The half this axis lacks, in its register names.
  CHECK(r.err.find("axis.y.limits_fitted is 0: no limit switch tells the opposite end") != std::string::npos);
  r = ctl(d, {"measure", "q"});
  CHECK(r.code() == 2);  // not an axis: a usage error, nothing written
}
