#include <catch2/catch.hpp>

#include "helpers.hpp"

using namespace persistence;

TEST_CASE("first start creates the settings from the register defaults", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  CHECK(report.outcome == OpenOutcome::created);
  CHECK_FALSE(report.settings_lost);
  CHECK(report.schema_version_found == 0);
  auto values = store.load();
  REQUIRE(values.size() == 5);
  CHECK(values["axis.x.mode"] == 3);
  CHECK(values["axis.x.home_position"] == -1500);
  CHECK(test::sql_int(dir.file("settings.db"), "PRAGMA user_version") == kSchemaVersion);
}

TEST_CASE("a committed write is there after reopening", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  {
    auto store = test::open_ok(dir.file("settings.db"), report);
    auto r = store.commit({{"axis.x.seek_feedrate", 4500}}, test::kTcp);
    REQUIRE(r);
    REQUIRE(r->size() == 1);
    CHECK((*r)[0].old_value == 3000);
    CHECK((*r)[0].new_value == 4500);
    CHECK(store.value("axis.x.seek_feedrate") == 4500);
  }
  auto store = test::open_ok(dir.file("settings.db"), report);
  CHECK(report.outcome == OpenOutcome::opened);
  CHECK(store.value("axis.x.seek_feedrate") == 4500);
}

TEST_CASE("the database runs in WAL mode with synchronous FULL", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  // synchronous is per connection, so it is read on the store's own
  // connection: FULL (2) makes every commit sync the WAL before it returns,
  // which is what survives a power cut (test_power_cut.cpp); NORMAL would
  // survive a kill only.
  auto expect_full = [](const SettingsStore& store) {
    auto d = store.durability();
    REQUIRE(d);
    CHECK(d->journal_mode == "wal");
    CHECK(d->synchronous == 2);
  };
  {
    auto store = test::open_ok(dir.file("settings.db"), report);
    REQUIRE(report.outcome == OpenOutcome::created);
    expect_full(store);
    REQUIRE(store.commit({{"axis.y.mode", 2}}, test::kTcp));
    CHECK(std::filesystem::exists(dir.file("settings.db-wal")));
  }
  auto store = test::open_ok(dir.file("settings.db"), report);  // the path that opens an existing file
  REQUIRE(report.outcome == OpenOutcome::opened);
  expect_full(store);
  CHECK(test::sql_int(dir.file("settings.db"), "SELECT count(*) FROM pragma_journal_mode WHERE journal_mode='wal'") ==
        1);
}

TEST_CASE("a multi-register write is one transaction with one audit row per change", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  auto r = store.commit({{"axis.x.mode", 4}, {"axis.y.mode", 2}, {"global.watchdog_ms", 500}}, test::kRtu);
  REQUIRE(r);
  CHECK(r->size() == 2);  // watchdog unchanged: not a change, not audited
  auto audit = store.recent_changes(10);
  REQUIRE(audit);
  REQUIRE(audit->size() == 2);
  CHECK((*audit)[0].name == "axis.y.mode");  // newest first
  CHECK((*audit)[0].transport == "rtu");
  CHECK((*audit)[0].client == "unit 5");
  CHECK((*audit)[0].old_value == 0);
  CHECK((*audit)[0].new_value == 2);
  CHECK((*audit)[1].name == "axis.x.mode");
  CHECK((*audit)[0].time_ms == (*audit)[1].time_ms);
}

TEST_CASE("a write naming an unknown register changes nothing", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  auto r = store.commit({{"axis.x.mode", 5}, {"axis.q.mode", 1}}, test::kTcp);
  REQUIRE_FALSE(r);
  CHECK(r.error().kind == ErrorKind::invalid);
  CHECK_THAT(r.error().message, Catch::Contains("axis.q.mode"));
  CHECK(store.value("axis.x.mode") == 3);
  CHECK(store.recent_changes(10)->empty());
}

TEST_CASE("a register added later gets its default without a migration", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  {
    auto store = test::open_ok(dir.file("settings.db"), report);
    REQUIRE(store.commit({{"axis.x.mode", 6}}, test::kTcp));
  }
  auto more = test::defaults();
  more.push_back({"axis.x.jog_feedrate", 1200});
  auto store = test::open_ok(dir.file("settings.db"), report, test::options(), more);
  CHECK(report.outcome == OpenOutcome::opened);
  REQUIRE(report.added_defaults == std::vector<std::string>{"axis.x.jog_feedrate"});
  CHECK(store.value("axis.x.jog_feedrate") == 1200);
  CHECK(store.value("axis.x.mode") == 6);
}

TEST_CASE("a stored setting no register uses any more is kept but ignored and reported", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  auto more = test::defaults();
  more.push_back({"axis.x.obsolete", 7});
  { auto store = test::open_ok(dir.file("settings.db"), report, test::options(), more); }
  {
    auto store = test::open_ok(dir.file("settings.db"), report);
    CHECK(report.unknown_names == std::vector<std::string>{"axis.x.obsolete"});
    CHECK_FALSE(store.value("axis.x.obsolete"));
    CHECK_FALSE(store.commit({{"axis.x.obsolete", 1}}, test::kTcp));
  }
  CHECK(test::sql_int(dir.file("settings.db"), "SELECT value FROM settings WHERE name='axis.x.obsolete'") == 7);
}

TEST_CASE("the audit log keeps only the newest rows up to its limit, pruned off the write path", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  auto o = test::options();
  o.audit_max_rows = 5;
  auto store = test::open_ok(dir.file("settings.db"), report, o);
  for (int i = 1; i <= 12; ++i) REQUIRE(store.commit({{"global.watchdog_ms", 1000 + i}}, test::kTcp));
  CHECK(store.recent_changes(100)->size() == 12);  // a write never waits for the pruning
  REQUIRE(store.prune_audit());
  auto audit = store.recent_changes(100);
  REQUIRE(audit);
  REQUIRE(audit->size() == 5);
  CHECK(audit->front().new_value == 1012);
  CHECK(audit->back().new_value == 1008);
  REQUIRE(store.set_limits(3, 100));
  REQUIRE(store.commit({{"global.watchdog_ms", 7}}, test::kTcp));
  REQUIRE(store.prune_audit());
  CHECK(store.recent_changes(100)->size() == 3);
}

TEST_CASE("a batch of several clients' writes is one transaction, each change audited with its own client",
          "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  const std::string file = dir.file("settings.db");
  {
    auto store = test::open_ok(file, report);
    const std::vector<SettingWrite> hmi{{"axis.x.seek_feedrate", 2000}},
        plc{{"axis.x.home_position", 3000}, {"axis.x.seek_feedrate", 2500}};
    const ChangeSource a{"tcp", "10.0.0.5:40000"}, b{"rtu", "unit 1"};
    auto changes = store.commit_batch({{&hmi, a}, {&plc, b}});
    REQUIRE(changes);
    REQUIRE(changes->size() == 2);
    REQUIRE((*changes)[0].size() == 1);
    REQUIRE((*changes)[1].size() == 2);
    CHECK((*changes)[1][1].old_value == 2000);  // in order: the second sees the first
    auto audit = store.recent_changes(10);
    REQUIRE(audit);
    REQUIRE(audit->size() == 3);
    CHECK(audit->back().client == "10.0.0.5:40000");
    CHECK(audit->front().client == "unit 1");
    // One unknown name refuses the whole batch.
    const std::vector<SettingWrite> bad{{"axis.x.nonsense", 1}};
    const std::vector<SettingWrite> good{{"global.watchdog_ms", 4000}};
    CHECK_FALSE(store.commit_batch({{&good, a}, {&bad, b}}));
    CHECK(store.value("global.watchdog_ms") == 500);
  }
  auto again = test::open_ok(file, report);
  CHECK(again.value("axis.x.seek_feedrate") == 2500);
  CHECK(again.value("axis.x.home_position") == 3000);
  CHECK(again.value("global.watchdog_ms") == 500);
}

TEST_CASE("a service change is one audit row with its client, changes no setting and is pruned like the others",
          "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  auto o = test::options();
  o.audit_max_rows = 3;
  auto store = test::open_ok(dir.file("settings.db"), report, o);
  const auto before = store.load();
  REQUIRE(store.audit({"axis.x.position", -1500, 12345}, test::kTcp));
  auto audit = store.recent_changes(10);
  REQUIRE(audit);
  REQUIRE(audit->size() == 1);
  CHECK(audit->front().name == "axis.x.position");
  CHECK(audit->front().old_value == -1500);
  CHECK(audit->front().new_value == 12345);
  CHECK(audit->front().transport == test::kTcp.transport);
  CHECK(audit->front().client == test::kTcp.client);
  CHECK(store.load() == before);
  for (int i = 0; i < 5; ++i) REQUIRE(store.audit({"axis.y.position", i, i + 1}, test::kTcp));
  CHECK(store.recent_changes(100)->size() == 3);
}

TEST_CASE("a read-only store answers writes with an error and keeps the value", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  { auto store = test::open_ok(dir.file("settings.db"), report); }
  auto o = test::options();
  o.read_only = true;
  auto store = test::open_ok(dir.file("settings.db"), report, o);
  auto r = store.commit({{"axis.x.mode", 1}}, test::kTcp);
  REQUIRE_FALSE(r);
  CHECK(r.error().kind == ErrorKind::read_only);
  CHECK(store.value("axis.x.mode") == 3);
}

TEST_CASE("the store can be moved and closed twice", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  auto a = test::open_ok(dir.file("settings.db"), report);
  SettingsStore b = std::move(a);
  REQUIRE(b.commit({{"axis.y.mode", 1}}, test::kTcp));
  b.close();
  b.close();
}
