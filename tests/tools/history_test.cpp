// The one reader of the history: homingctl history on a database built here
// (known corrections), and homing-settings pointing to it.
#include <catch2/catch.hpp>

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
}  // namespace

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
