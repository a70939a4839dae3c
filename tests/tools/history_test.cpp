// The one reader of the history: homingctl history on a database built here
// (known corrections), and homing-settings pointing to it.
#include <catch2/catch.hpp>

#include <regex>

#include "persistence/settings_store.hpp"
#include "tools_helpers.hpp"

#ifndef HOMING_SETTINGS_PATH
#error "HOMING_SETTINGS_PATH must be defined"
#endif

using namespace tools_test;

namespace {
// A database whose last runs homed X with these home corrections, oldest first.
void record_runs(const std::string& db, std::initializer_list<double> x_corrections) {
  persistence::OpenReport report;
  auto store = persistence::SettingsStore::open(db, {}, report);
  REQUIRE(store);
  std::int64_t t = 1714564987000;
  for (double x : x_corrections) {
    persistence::HomingRun run;
    run.start_ms = t;
    run.end_ms = t + 2000;
    run.axes = 0b1;
    run.axis[0] = {true, x, 1200};
    REQUIRE(store->record_homing_run(run));
    t += 60000;
  }
}
// A database whose runs homed X with these hysteresis figures, and Y (a
// gantry slave) with a skew, oldest first; every third run homed Z only.
void record_health(const std::string& db, std::initializer_list<double> x_hysteresis) {
  persistence::OpenReport report;
  auto store = persistence::SettingsStore::open(db, {}, report);
  REQUIRE(store);
  std::int64_t t = 1714564987000;
  int k = 0;
  for (double h : x_hysteresis) {
    persistence::HomingRun run;
    run.start_ms = t;
    run.end_ms = t + 2000;
    run.axes = 0b011;
    persistence::AxisHealth x;
    x.latch_passes = 3;
    x.latch_spread_mm = 0.004;
    x.latch_sigma_mm = 0.0015;
    x.hysteresis_mm = h;
    x.seek_latch_mm = 0.002;
    x.chatter_edges = k % 2;
    run.axis[0] = {true, 0.001, 1200, persistence::Excluded::no, x};
    persistence::AxisHealth y = x;
    y.gantry_skew_mm = 0.01 * k;
    run.axis[1] = {true, 0.001, 1200, persistence::Excluded::no, y};
    REQUIRE(store->record_homing_run(run));
    if (++k % 3 == 0) {
      persistence::HomingRun z;
      z.start_ms = t + 3000;
      z.end_ms = t + 4000;
      z.axes = 0b100;
      z.axis[2] = {true, 0.001, 900, persistence::Excluded::no, x};
      REQUIRE(store->record_homing_run(z));
    }
    t += 60000;
  }
}

}  // namespace

TEST_CASE("homingctl history --trend prints an axis's health figures cycle by cycle, oldest first") {
  TempDir dir;
  const std::string db = dir.file("history.db");
  record_health(db, {0.05, 0.06, 0.08, 0.11, 0.15});
  auto r = run_program({HOMINGCTL_PATH, "history", "--db", db, "--trend", "x", "-n", "4"}, 30s);
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("health figures of X (oldest first, 4 cycles, lengths in mm):") != std::string::npos);
  CHECK(r.out.find("hysteresis") != std::string::npos);
  // The last 4 of X's cycles, oldest first: 0.06 ... 0.15; the first is left out.
  const auto first = r.out.find("    0.0600 ");
  const auto last = r.out.find("    0.1500 ");
  CHECK(first != std::string::npos);
  CHECK(last != std::string::npos);
  CHECK(first < last);
  CHECK(r.out.find("    0.0500 ") == std::string::npos);
  auto j = json_of(run_program({HOMINGCTL_PATH, "history", "--json", "--db", db, "--trend", "y"}, 30s));
  CHECK(j["axis"] == "y");
  CHECK(j["unit"] == "mm");
  REQUIRE(j["cycles"].size() == 5);
  CHECK(j["cycles"][0]["gantry_skew"].get<double>() == Approx(0.0));
  CHECK(j["cycles"][4]["gantry_skew"].get<double>() == Approx(0.04));
  CHECK(j["cycles"][4]["hysteresis"].get<double>() == Approx(0.15));
  CHECK(j["cycles"][0]["run"].get<int>() < j["cycles"][1]["run"].get<int>());
  // Not an axis: a usage error that names it.
  r = run_program({HOMINGCTL_PATH, "history", "--db", db, "--trend", "q"}, 30s);
  CHECK(r.code() == 2);
  CHECK(r.err.find("'q' is not an axis") != std::string::npos);
  r = run_program({HOMINGCTL_PATH, "history", "--db", db, "--svg", dir.file("t.svg")}, 30s);
  CHECK(r.code() == 2);
  CHECK(r.err.find("--trend") != std::string::npos);
}

TEST_CASE("homingctl history --trend --svg draws a well-formed SVG with a point per cycle of the axis") {
  TempDir dir;
  const std::string db = dir.file("history.db");
  record_health(db, {0.05, 0.06, 0.08, 0.11, 0.15, 0.2});
  const std::string svg_path = dir.file("y.svg");
  auto r = run_program({HOMINGCTL_PATH, "history", "--db", db, "--trend", "y", "--svg", svg_path}, 30s);
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out == "Y: 6 cycles drawn to " + svg_path + "\n");
  const std::string svg = read_file(svg_path);
  CHECK(svg.rfind("<svg xmlns=\"http://www.w3.org/2000/svg\"", 0) == 0);
  // Well-formed XML: Debian's python parses it.
  auto xml = run_program({"/usr/bin/python3", "-c", "import sys, xml.etree.ElementTree as E; E.parse(sys.argv[1])",
                          svg_path}, 30s);
  INFO(xml.err);
  CHECK(xml.code() == 0);
  CHECK(svg.find("Health trend, axis Y: 6 cycles") != std::string::npos);
  CHECK(svg.find("hysteresis (mm)") != std::string::npos);
  CHECK(svg.find("gantry skew (mm)") != std::string::npos);
  CHECK(count_of(svg, "class=\"point\" data-figure=\"hysteresis\"") == 6);
  CHECK(count_of(svg, "class=\"point\" data-figure=\"gantry_skew\"") == 6);
  CHECK(count_of(svg, "class=\"trend\"") == count_of(svg, "class=\"frame\""));
  for (const char* value : {"0.05", "0.06", "0.08", "0.11", "0.15", "0.2"}) {
    INFO(value);
    CHECK(std::regex_search(svg, std::regex(std::string("data-figure=\"hysteresis\" data-run=\"[0-9]+\" data-value=\"") +
                                            value + "\"")));
  }
  // Y's runs only: the runs of Z alone are not Y's cycles.
  auto j = json_of(run_program({HOMINGCTL_PATH, "history", "--json", "--db", db, "--trend", "y"}, 30s));
  for (const auto& c : j["cycles"])
    CHECK(svg.find("data-run=\"" + std::to_string(c["run"].get<int>()) + "\"") != std::string::npos);
  // One latch spread and sigma plot too (3 passes), no index plot (no index pulse was measured).
  CHECK(svg.find("data-figure=\"latch_spread\"") != std::string::npos);
  CHECK(svg.find("data-figure=\"index_distance\"") == std::string::npos);
}

TEST_CASE("homingctl history --corrections summarises each axis's home correction over its last runs") {
  TempDir dir;
  const std::string db = dir.file("history.db");
  record_runs(db, {0.010, 0.012, 0.014});

  auto r = run_program({HOMINGCTL_PATH, "history", "--db", db, "--corrections", "2"}, 30s);
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
    CHECK(r.out.find("homing runs (newest first, 3 shown):") != std::string::npos);
    CHECK(r.out.find("home corrections per axis (last 2 runs):") != std::string::npos);
    CHECK(r.out.find("\n  X     2      +0.0130    0.0020      0.0014\n") != std::string::npos);
    CHECK(r.out.find("\n  Y ") == std::string::npos);  // no run homed Y
  }
  auto j = json_of(run_program({HOMINGCTL_PATH, "history", "--json", "--db", db, "--corrections", "2"}, 30s));
  REQUIRE(j["corrections"].size() == 1);
  CHECK(j["corrections"][0]["axis"] == "x");
  CHECK(j["corrections"][0]["runs"] == 2);
  CHECK(j["corrections"][0]["mean"].get<double>() == Approx(0.013));
  CHECK(j["corrections"][0]["spread"].get<double>() == Approx(0.002));

  r = run_program({HOMINGCTL_PATH, "history", "--db", db}, 30s);
  CHECK(r.code() == 0);
  CHECK(r.out.find("home corrections") == std::string::npos);  // only when asked for
  j = json_of(run_program({HOMINGCTL_PATH, "history", "--json", "--db", db}, 30s));
  CHECK_FALSE(j.contains("corrections"));
}

TEST_CASE("homing-settings leaves the history to homingctl history and says so") {
  for (const char* moved : {"history", "audit", "corrections"}) {
    auto r = run_program({HOMING_SETTINGS_PATH, "--db", "machine.db", moved}, 30s);
    SHOW(r);
    CHECK(r.code() == 2);
    CHECK(r.err.find("homingctl history --db machine.db") != std::string::npos);
  }
}

TEST_CASE("homing-settings without --db reads homingd.db, the daemon's own default") {
  TempDir dir;
  {
    persistence::OpenReport report;
    REQUIRE(persistence::SettingsStore::open(dir.file("homingd.db"), {{"axis.x.pull_off", 2500}}, report));
  }
  auto r = run_program({"/bin/sh", "-c", "cd '" + dir.path().string() + "' && exec '" + std::string(HOMING_SETTINGS_PATH) + "' show"}, 30s);
  SHOW(r);
  CHECK(r.code() == 0);
  CHECK(r.out == "axis.x.pull_off = 2500\n");
}

TEST_CASE("homing-settings shows, exports and checks a database without the module") {
  TempDir dir;
  const std::string db = dir.file("settings.db");
  {
    persistence::OpenReport report;
    REQUIRE(persistence::SettingsStore::open(db, {{"axis.x.pull_off", 1000}}, report));
  }
  auto r = run_program({HOMING_SETTINGS_PATH, "--db", db, "show"}, 30s);
  SHOW(r);
  CHECK(r.code() == 0);
  CHECK(r.out == "axis.x.pull_off = 1000\n");
  r = run_program({HOMING_SETTINGS_PATH, "--db", db, "check"}, 30s);
  CHECK(r.code() == 0);
  CHECK(r.out.find(": ok (schema v") != std::string::npos);
  r = run_program({HOMING_SETTINGS_PATH, "--db", db, "export", dir.file("out.toml")}, 30s);
  CHECK(r.code() == 0);
  // Engineering values, as homingctl export and homingd --export-settings write them.
  const std::string exported = read_file(dir.file("out.toml"));
  CHECK(exported.find("format_version = 2\n") != std::string::npos);
  CHECK(exported.find("\naxis.x.pull_off = 1.0  # mm\n") != std::string::npos);
}
