// Databases written by earlier firmware (schema built here with the SQL those
// versions shipped) upgrade to the current schema and keep their values.
#include <catch2/catch.hpp>

#include <iterator>

#include "helpers.hpp"

using namespace persistence;

namespace {

const std::string kV1Sql = R"(
CREATE TABLE settings(name TEXT PRIMARY KEY NOT NULL, value INTEGER NOT NULL) WITHOUT ROWID;
PRAGMA user_version = 1;
)";

const std::string kV2Sql = kV1Sql + R"(
CREATE TABLE audit(id INTEGER PRIMARY KEY AUTOINCREMENT, time_ms INTEGER NOT NULL, source TEXT NOT NULL,
                   name TEXT NOT NULL, old_value INTEGER, new_value INTEGER NOT NULL);
PRAGMA user_version = 2;
)";

// What version 3 shipped for the history (its audit table is version 2's, upgraded).
const std::string kV3HistorySql = R"(
CREATE TABLE meta(key TEXT PRIMARY KEY NOT NULL, value TEXT NOT NULL) WITHOUT ROWID;
CREATE TABLE homing_runs(id INTEGER PRIMARY KEY AUTOINCREMENT, start_ms INTEGER NOT NULL, end_ms INTEGER NOT NULL,
                         axes INTEGER NOT NULL, result INTEGER NOT NULL, alarm_axis INTEGER NOT NULL);
CREATE TABLE homing_axes(run_id INTEGER NOT NULL, axis INTEGER NOT NULL, correction_mm REAL,
                         duration_ms INTEGER NOT NULL, PRIMARY KEY(run_id, axis)) WITHOUT ROWID;
CREATE INDEX homing_axes_by_axis ON homing_axes(axis, run_id);
)";

const std::string kV3Sql = kV1Sql + R"(
CREATE TABLE audit(id INTEGER PRIMARY KEY AUTOINCREMENT, time_ms INTEGER NOT NULL, transport TEXT NOT NULL,
                   client TEXT NOT NULL, name TEXT NOT NULL, old_value INTEGER NOT NULL, new_value INTEGER NOT NULL);
)" + kV3HistorySql + "PRAGMA user_version = 3;\n";

// What version 4 shipped: version 3 with the reason a correction is excluded.
const std::string kV4Sql = kV3Sql + R"(
ALTER TABLE homing_axes ADD COLUMN excluded INTEGER NOT NULL DEFAULT 0;
PRAGMA user_version = 4;
)";

// What version 5 shipped: version 4 with the switch health figures.
const std::string kV5Sql = kV4Sql + R"(
ALTER TABLE homing_axes ADD COLUMN latch_passes INTEGER;
ALTER TABLE homing_axes ADD COLUMN latch_spread_mm REAL;
ALTER TABLE homing_axes ADD COLUMN latch_sigma_mm REAL;
ALTER TABLE homing_axes ADD COLUMN hysteresis_mm REAL;
ALTER TABLE homing_axes ADD COLUMN seek_latch_mm REAL;
ALTER TABLE homing_axes ADD COLUMN chatter_edges INTEGER;
ALTER TABLE homing_axes ADD COLUMN index_distance_mm REAL;
ALTER TABLE homing_axes ADD COLUMN index_near_edge INTEGER;
ALTER TABLE homing_axes ADD COLUMN gantry_skew_mm REAL;
PRAGMA user_version = 5;
)";

// What version 6 shipped: version 5 with the last stops and the simulator's carriages.
const std::string kV6Sql = kV5Sql + R"(
CREATE TABLE last_stop(axis INTEGER PRIMARY KEY NOT NULL, clean INTEGER NOT NULL, position_mm REAL NOT NULL,
                       mode INTEGER NOT NULL, direction INTEGER NOT NULL, sensor_nc INTEGER NOT NULL,
                       slave_of INTEGER NOT NULL, slave_mode INTEGER NOT NULL, pull_off_mm REAL NOT NULL,
                       switch_compensation_mm REAL NOT NULL, home_position_mm REAL NOT NULL,
                       time_ms INTEGER NOT NULL) WITHOUT ROWID;
CREATE TABLE sim_carriages(axis INTEGER PRIMARY KEY NOT NULL, actual_mm REAL NOT NULL) WITHOUT ROWID;
PRAGMA user_version = 6;
)";

}  // namespace

TEST_CASE("a version 6 database upgrades: each clean last stop keeps the home cam edge it was homed on",
          "[persistence][migration][trust]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  // X a home cam on its far edge, Y one on its near edge, Z a switch axis
  // whose cam_edge setting places nothing, A a home cam on the default edge
  // (no row in settings).
  test::sql_exec(db, kV6Sql + R"(
    INSERT INTO settings VALUES('axis.x.mode', 11);
    INSERT INTO settings VALUES('axis.x.cam_edge', 1);
    INSERT INTO settings VALUES('axis.y.cam_edge', 0);
    INSERT INTO settings VALUES('axis.z.cam_edge', 1);
    INSERT INTO last_stop VALUES(0, 1, 120.5, 11, 1, 0, 0, 0, 2.0, 0.0, 0.0, 50);
    INSERT INTO last_stop VALUES(1, 1, 121.0, 11, 1, 0, 0, 0, 2.0, 0.0, 0.0, 50);
    INSERT INTO last_stop VALUES(2, 1, -4.0, 3, 0, 0, 0, 0, 1.0, 0.0, 0.0, 50);
    INSERT INTO last_stop VALUES(3, 0, 30.0, 11, 0, 0, 0, 0, 1.0, 0.0, 0.0, 50);
    INSERT INTO sim_carriages VALUES(0, 120.5);
  )");
  OpenReport report;
  auto store = test::open_ok(db, report);
  CHECK(report.schema_version_found == 6);
  CHECK(test::sql_int(db, "PRAGMA user_version") == kSchemaVersion);
  auto stops = store.last_stops();
  REQUIRE(stops);
  REQUIRE((*stops)[0]);
  CHECK((*stops)[0]->frame.cam_edge == 1);
  CHECK((*stops)[0]->position_mm == 120.5);
  CHECK((*stops)[0]->frame.pull_off_mm == 2.0);
  REQUIRE((*stops)[1]);
  CHECK((*stops)[1]->frame.cam_edge == 0);
  REQUIRE((*stops)[2]);
  CHECK((*stops)[2]->frame.cam_edge == 0);
  REQUIRE((*stops)[3]);
  CHECK((*stops)[3]->frame.cam_edge == 0);
  CHECK_FALSE((*stops)[3]->clean);
  auto carriages = store.sim_carriages();
  REQUIRE(carriages);
  CHECK((*carriages)[0] == 120.5);
  // And the edge is kept from then on.
  LastStops one{};
  one[4] = AxisLastStop{true, 7.5, StoredFrame{11, 0, false, 0, 0, 1.0, 0.0, 0.0, 1}, 77};
  REQUIRE(store.record_last_stops(one));
  stops = store.last_stops();
  REQUIRE(stops);
  CHECK((*stops)[4] == one[4]);
}

TEST_CASE("a version 5 database upgrades: its runs stay, no axis has a last stop, and the last stops are kept from then on",
          "[persistence][migration][trust]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  test::sql_exec(db, kV5Sql + R"(
    INSERT INTO settings VALUES('axis.x.mode', 3);
    INSERT INTO homing_runs(id, start_ms, end_ms, axes, result, alarm_axis) VALUES(1, 100, 200, 1, 0, -1);
    INSERT INTO homing_axes(run_id, axis, correction_mm, duration_ms, excluded, hysteresis_mm)
      VALUES(1, 0, 0.012, 100, 0, 0.05);
  )");
  OpenReport report;
  auto store = test::open_ok(db, report);
  CHECK(report.schema_version_found == 5);
  CHECK(test::sql_int(db, "PRAGMA user_version") == kSchemaVersion);
  CHECK(store.value("axis.x.mode") == 3);
  auto runs = store.recent_runs(10);
  REQUIRE(runs);
  REQUIRE(runs->size() == 1);
  auto stops = store.last_stops();
  REQUIRE(stops);
  for (const auto& s : *stops) CHECK_FALSE(s.has_value());
  LastStops one{};
  one[2] = AxisLastStop{true, 12.5, StoredFrame{2, 1, false, 0, 0, 1.0, 0.0, 0.0, 0}, 77};
  REQUIRE(store.record_last_stops(one));
  stops = store.last_stops();
  REQUIRE(stops);
  CHECK((*stops)[2] == one[2]);
}

TEST_CASE("a version 4 database upgrades: its runs stay, without health figures, and new runs keep theirs",
          "[persistence][migration][health]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  test::sql_exec(db, kV4Sql + R"(
    INSERT INTO settings VALUES('axis.x.mode', 3);
    INSERT INTO homing_runs(id, start_ms, end_ms, axes, result, alarm_axis) VALUES(1, 100, 200, 1, 0, -1),
                                                                                (2, 300, 400, 1, 0, -1);
    INSERT INTO homing_axes(run_id, axis, correction_mm, duration_ms, excluded) VALUES(1, 0, NULL, 100, 1),
                                                                                      (2, 0, 0.012, 100, 0);
  )");
  OpenReport report;
  auto store = test::open_ok(db, report);
  CHECK(report.schema_version_found == 4);
  CHECK(test::sql_int(db, "PRAGMA user_version") == kSchemaVersion);
  CHECK(store.value("axis.x.mode") == 3);
  auto runs = store.recent_runs(10);
  REQUIRE(runs);
  REQUIRE(runs->size() == 2);
  CHECK((*runs)[0].axis[0].correction_mm == Approx(0.012));
  CHECK((*runs)[1].axis[0].excluded == Excluded::not_homed_before);
  CHECK_FALSE((*runs)[0].axis[0].health);
  CHECK(store.correction_summary(0, 10)->count == 1);
  CHECK(store.health_history(0, 10)->empty());  // the old runs measured nothing the history kept
  HomingRun run;
  AxisHealth h;
  h.latch_passes = 1;
  h.hysteresis_mm = 0.05;
  h.gantry_skew_mm = 0.3;
  run.axis[0] = {true, 0.011, 50, Excluded::no, h};
  auto id = store.record_homing_run(run);
  REQUIRE(id);
  CHECK(*id == 3);
  auto health = store.health_history(0, 10);
  REQUIRE(health);
  REQUIRE(health->size() == 1);
  CHECK(health->front().run_id == 3);
  CHECK(health->front().health == h);
  CHECK(std::filesystem::exists(db + ".pre-v" + std::to_string(kSchemaVersion)));
}

TEST_CASE("a version 3 database upgrades: failed runs are marked excluded, earlier corrections stay counted",
          "[persistence][migration]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  test::sql_exec(db, kV3Sql + R"(
    INSERT INTO homing_runs(id, start_ms, end_ms, axes, result, alarm_axis) VALUES(1, 100, 200, 1, 0, -1),
                                                                                (2, 300, 400, 1, 5, 0);
    INSERT INTO homing_axes(run_id, axis, correction_mm, duration_ms) VALUES(1, 0, 0.012, 100), (2, 0, NULL, 100);
  )");
  OpenReport report;
  auto store = test::open_ok(db, report);
  CHECK(report.schema_version_found == 3);
  CHECK(test::sql_int(db, "PRAGMA user_version") == kSchemaVersion);
  auto runs = store.recent_runs(10);
  REQUIRE(runs);
  REQUIRE(runs->size() == 2);
  CHECK((*runs)[0].axis[0].excluded == Excluded::cycle_failed);
  CHECK((*runs)[1].axis[0].excluded == Excluded::no);
  CHECK((*runs)[1].axis[0].correction_mm == Approx(0.012));
  CHECK(store.correction_summary(0, 10)->count == 1);
  // New runs continue after the migrated ones, with their reason.
  HomingRun run;
  run.axis[0] = {true, std::nullopt, 50, Excluded::not_homed_before};
  auto id = store.record_homing_run(run);
  REQUIRE(id);
  CHECK(*id == 3);
  CHECK(store.recent_runs(1)->front().axis[0].excluded == Excluded::not_homed_before);
}

TEST_CASE("a version 1 database upgrades and keeps its settings", "[persistence][migration]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  test::sql_exec(db, kV1Sql + "INSERT INTO settings VALUES('axis.x.mode', 8), ('axis.y.mode', 2);");
  OpenReport report;
  auto store = test::open_ok(db, report);
  CHECK(report.outcome == OpenOutcome::opened);
  CHECK(report.schema_version_found == 1);
  CHECK(store.value("axis.x.mode") == 8);
  CHECK(store.value("axis.y.mode") == 2);
  CHECK(store.value("global.watchdog_ms") == 500);  // not in v1 file: default added
  CHECK(test::sql_int(db, "PRAGMA user_version") == kSchemaVersion);
  // The upgraded database works: audit and history.
  REQUIRE(store.commit({{"axis.x.mode", 3}}, test::kTcp));
  REQUIRE(store.record_homing_run(HomingRun{}));
  CHECK(std::filesystem::exists(db + ".pre-v" + std::to_string(kSchemaVersion)));
}

TEST_CASE("a version 2 database upgrades, keeping settings and splitting the audit source", "[persistence][migration]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  test::sql_exec(db, kV2Sql + R"(
    INSERT INTO settings VALUES('axis.x.seek_feedrate', 2500);
    INSERT INTO audit(time_ms, source, name, old_value, new_value)
      VALUES(100, 'tcp 10.0.0.5:502', 'axis.x.seek_feedrate', 3000, 2500),
            (200, 'cli', 'axis.x.seek_feedrate', NULL, 2500);
  )");
  OpenReport report;
  auto store = test::open_ok(db, report);
  CHECK(report.schema_version_found == 2);
  CHECK(store.value("axis.x.seek_feedrate") == 2500);
  auto audit = store.recent_changes(10);
  REQUIRE(audit);
  REQUIRE(audit->size() == 2);
  CHECK((*audit)[1].transport == "tcp");
  CHECK((*audit)[1].client == "10.0.0.5:502");
  CHECK((*audit)[1].old_value == 3000);
  CHECK((*audit)[0].transport == "cli");
  CHECK((*audit)[0].client == "");
  CHECK((*audit)[0].old_value == 2500);
  // New audit rows continue after the migrated ones.
  REQUIRE(store.commit({{"axis.x.seek_feedrate", 2600}}, test::kTcp));
  CHECK(store.recent_changes(1)->front().id == 3);
}

TEST_CASE("an upgraded database opens as current the next time", "[persistence][migration]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  test::sql_exec(db, kV1Sql);
  OpenReport report;
  { test::open_ok(db, report); }
  test::open_ok(db, report);
  CHECK(report.schema_version_found == kSchemaVersion);
}

TEST_CASE("a database from a newer firmware is refused and left untouched", "[persistence][migration]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  test::sql_exec(db, kV2Sql + "PRAGMA user_version = 99;");
  OpenReport report;
  auto store = SettingsStore::open(db, test::defaults(), report, test::options());
  REQUIRE_FALSE(store);
  CHECK(store.error().kind == ErrorKind::version);
  CHECK_THAT(store.error().message, Catch::Contains("newer firmware"));
  CHECK(test::sql_int(db, "PRAGMA user_version") == 99);
}

TEST_CASE("a database of another program is refused by name and left byte for byte as it was",
          "[persistence][migration]") {
  test::TempDir dir;
  const auto db = dir.file("tooltable.db");
  test::sql_exec(db, "CREATE TABLE tools(number INTEGER PRIMARY KEY, diameter REAL);"
                     "INSERT INTO tools VALUES (1, 6.0);");
  const auto bytes = [&] {
    std::ifstream in(db, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string before = bytes();
  REQUIRE_FALSE(before.empty());
  OpenReport report;
  auto store = SettingsStore::open(db, test::defaults(), report, test::options());
  REQUIRE_FALSE(store);
  CHECK(store.error().kind == ErrorKind::invalid);
  CHECK_THAT(store.error().message, Catch::Contains("another program") && Catch::Contains("tools") &&
                                        Catch::Contains("left untouched"));
  CHECK(bytes() == before);  // its journal mode too: still a rollback journal, no WAL
  CHECK_FALSE(std::filesystem::exists(db + "-wal"));
  CHECK_FALSE(std::filesystem::exists(db + ".bak"));
  CHECK(test::sql_int(db, "SELECT count(*) FROM tools") == 1);
}

TEST_CASE("a database of another program is refused whatever its schema version and its WAL is left unread",
          "[persistence][migration]") {
  test::TempDir dir;
  const auto db = dir.file("other.db");
  const auto bytes = [](const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  SECTION("a schema version of its own") {
    test::sql_exec(db, "CREATE TABLE jobs(id INTEGER PRIMARY KEY); PRAGMA user_version = 3;");
    const std::string before = bytes(db);
    OpenReport report;
    auto store = SettingsStore::open(db, test::defaults(), report, test::options());
    REQUIRE_FALSE(store);
    CHECK(store.error().kind == ErrorKind::invalid);
    CHECK_THAT(store.error().message, Catch::Contains("another program") && Catch::Contains("jobs"));
    CHECK(bytes(db) == before);
    CHECK(test::sql_int(db, "PRAGMA user_version") == 3);
  }
  SECTION("in WAL mode with a WAL not yet checkpointed") {
    sqlite3* raw = nullptr;
    REQUIRE(sqlite3_open(db.c_str(), &raw) == SQLITE_OK);
    int off = 1;
    sqlite3_db_config(raw, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, &off);
    REQUIRE(sqlite3_exec(raw, "PRAGMA journal_mode=WAL; PRAGMA wal_autocheckpoint=0; CREATE TABLE jobs(id INTEGER); "
                              "INSERT INTO jobs VALUES (1);",
                         nullptr, nullptr, nullptr) == SQLITE_OK);
    sqlite3_close(raw);
    REQUIRE(std::filesystem::exists(db + "-wal"));
    const std::string main_before = bytes(db), wal_before = bytes(db + "-wal");
    OpenReport report;
    auto store = SettingsStore::open(db, test::defaults(), report, test::options());
    REQUIRE_FALSE(store);
    CHECK(store.error().kind == ErrorKind::invalid);
    CHECK(bytes(db) == main_before);
    REQUIRE(std::filesystem::exists(db + "-wal"));
    CHECK(bytes(db + "-wal") == wal_before);
  }
}

TEST_CASE("homingd's own database that lost its schema version is not taken for another program's",
          "[persistence][migration]") {
  // A repair by `sqlite3 db .dump | sqlite3 new` drops user_version.
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  test::sql_exec(db, "CREATE TABLE settings(name TEXT PRIMARY KEY NOT NULL, value INTEGER NOT NULL) WITHOUT ROWID;");
  OpenReport report;
  auto store = SettingsStore::open(db, test::defaults(), report, test::options());
  if (!store) CHECK_THAT(store.error().message, !Catch::Contains("another program"));
}

TEST_CASE("a database of another program with a settings(name, value) table of its own is refused and left as it was",
          "[persistence][migration]") {
  test::TempDir dir;
  const auto db = dir.file("app.db");
  test::sql_exec(db, "CREATE TABLE settings(name TEXT PRIMARY KEY, value TEXT);"
                     "INSERT INTO settings VALUES ('theme', 'dark'), ('language', 'de');");
  const auto bytes = [&] {
    std::ifstream in(db, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string before = bytes();
  OpenReport report;
  auto store = SettingsStore::open(db, test::defaults(), report, test::options());
  REQUIRE_FALSE(store);
  CHECK(store.error().kind == ErrorKind::invalid);
  CHECK_THAT(store.error().message, Catch::Contains("another program") &&
                                        Catch::Contains("its settings table holds 2 row(s), none of them homingd's"));
  CHECK(bytes() == before);
  CHECK(test::sql_int(db, "SELECT count(*) FROM settings") == 2);
}

TEST_CASE("homingd's own database is still taken for its own when its settings hold only some registers",
          "[persistence][migration]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  test::sql_exec(db, "CREATE TABLE settings(name TEXT PRIMARY KEY NOT NULL, value INTEGER NOT NULL) WITHOUT ROWID;"
                     "INSERT INTO settings VALUES ('axis.x.seek_feedrate', 2500); PRAGMA user_version = 1;");
  OpenReport report;
  auto store = SettingsStore::open(db, test::defaults(), report, test::options());
  REQUIRE(store);
  CHECK(store->value("axis.x.seek_feedrate") == 2500);
}
