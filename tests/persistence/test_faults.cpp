// Disk faults and damaged databases. A full or read-only disk is simulated by
// the "faulty" SQLite VFS (fault_vfs.hpp): we run as root, where chmod would
// not stop writes, and mounting is not available.
#include <catch2/catch.hpp>

#include <future>
#include <thread>

#include "fault_vfs.hpp"
#include "helpers.hpp"

using namespace persistence;

namespace {

StoreOptions faulty_options() {
  fault_vfs::install();
  auto o = test::options();
  o.vfs = fault_vfs::kName;
  return o;
}

// A store on the faulty VFS whose owner writes the backups (none on commit),
// one committed write in it (axis.x.mode = 4) not yet backed up.
SettingsStore store_with_backup_due(const std::string& db) {
  OpenReport report;
  auto o = faulty_options();
  o.backup_on_commit = false;
  auto store = test::open_ok(db, report, o);
  REQUIRE(store.commit({{"axis.x.mode", 4}}, test::kTcp));
  return store;
}

template <class Result>
struct BesideBackup {
  bool answered = false;  // within 10 s, while the backup was held
  Result result{};
  Status backed_up;
};

// Runs `backup` on a thread until the fault VFS holds it half written, then
// `ask` beside it; the backup is let go after `ask` answered or 10 s passed.
template <class Backup, class Ask>
auto beside_a_held_backup(Backup backup, Ask ask) {
  BesideBackup<decltype(ask())> out;
  fault_vfs::BackupGate gate;
  std::thread backing_up([&] { out.backed_up = backup(); });
  if (!gate.held(std::chrono::seconds(10))) {
    gate.release();
    backing_up.join();
    FAIL("the backup never reached the fault VFS's gate");
  }
  auto asked = std::async(std::launch::async, ask);
  out.answered = asked.wait_for(std::chrono::seconds(10)) == std::future_status::ready;
  gate.release();
  backing_up.join();
  out.result = asked.get();
  return out;
}

void check_fault_keeps_old_value(fault_vfs::Fault fault, ErrorKind expected_kind) {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  {
    auto store = test::open_ok(db, report, faulty_options());
    REQUIRE(store.commit({{"axis.x.seek_feedrate", 4000}}, test::kTcp));
    {
      fault_vfs::Scoped f(fault);
      auto r = store.commit({{"axis.x.seek_feedrate", 5000}, {"axis.y.mode", 4}}, test::kTcp);
      REQUIRE_FALSE(r);
      CHECK(fault_vfs::faults_hit() > 0);
      CHECK(r.error().kind == expected_kind);
      CHECK_THAT(r.error().message, Catch::Contains(db));
      CHECK_THAT(r.error().message, Catch::Contains("old settings stay in force"));
      // In memory: old values.
      CHECK(store.value("axis.x.seek_feedrate") == 4000);
      CHECK(store.value("axis.y.mode") == 0);
      // Still faulty: still refused, still old.
      CHECK_FALSE(store.commit({{"axis.y.mode", 4}}, test::kTcp));
      CHECK(store.value("axis.y.mode") == 0);
    }
    // The disk recovers: writes work again on the same store.
    REQUIRE(store.commit({{"global.watchdog_ms", 900}}, test::kTcp));
    CHECK(store.value("axis.x.seek_feedrate") == 4000);
    auto audit = store.recent_changes(10);
    REQUIRE(audit);
    CHECK(audit->size() == 2);  // 4000 and 900; nothing of the refused writes
  }
  // On disk: old values, intact.
  auto store = test::open_ok(db, report);
  CHECK(report.outcome == OpenOutcome::opened);
  CHECK(store.value("axis.x.seek_feedrate") == 4000);
  CHECK(store.value("axis.y.mode") == 0);
  CHECK(store.value("global.watchdog_ms") == 900);
  CHECK(store.check_integrity());
}

}  // namespace

TEST_CASE("a full disk answers the write with an error and keeps the old value everywhere", "[persistence][fault]") {
  check_fault_keeps_old_value(fault_vfs::Fault::disk_full, ErrorKind::disk_full);
}

TEST_CASE("a read-only disk answers the write with an error and keeps the old value everywhere",
          "[persistence][fault]") {
  check_fault_keeps_old_value(fault_vfs::Fault::read_only, ErrorKind::read_only);
}

TEST_CASE("a disk that fails in the middle of a commit keeps the old value everywhere", "[persistence][fault]") {
  // Let some page writes of the commit through before the disk fills.
  for (int writes_before : {1, 2, 3}) {
    test::TempDir dir;
    const auto db = dir.file("settings.db");
    OpenReport report;
    {
      auto store = test::open_ok(db, report, faulty_options());
      std::vector<SettingWrite> many;
      for (const auto& d : test::defaults()) many.push_back({d.name, d.value + 17});
      fault_vfs::Scoped f(fault_vfs::Fault::disk_full, writes_before);
      auto r = store.commit(many, test::kTcp);
      if (r) continue;  // the commit needed fewer writes than allowed: nothing to check
      CHECK(store.value("axis.x.mode") == 3);
    }
    auto store = test::open_ok(db, report);
    CHECK(report.outcome == OpenOutcome::opened);
    CHECK(store.value("axis.x.mode") == 3);
    CHECK(store.value("global.watchdog_ms") == 500);
  }
}

TEST_CASE("a homing run that cannot be recorded returns an error", "[persistence][fault]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report, faulty_options());
  fault_vfs::Scoped f(fault_vfs::Fault::disk_full);
  auto r = store.record_homing_run(HomingRun{});
  REQUIRE_FALSE(r);
  CHECK(r.error().kind == ErrorKind::disk_full);
}

TEST_CASE("each committed change batch leaves a verified backup, keeping the last two", "[persistence][backup]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  auto store = test::open_ok(db, report);
  REQUIRE(store.commit({{"axis.x.mode", 4}}, test::kTcp));
  REQUIRE(std::filesystem::exists(db + ".bak"));
  CHECK(test::sql_int(db + ".bak", "SELECT value FROM settings WHERE name='axis.x.mode'") == 4);
  REQUIRE(store.commit({{"axis.x.mode", 5}}, test::kTcp));
  CHECK(test::sql_int(db + ".bak", "SELECT value FROM settings WHERE name='axis.x.mode'") == 5);
  CHECK(test::sql_int(db + ".bak.1", "SELECT value FROM settings WHERE name='axis.x.mode'") == 4);
  CHECK_FALSE(std::filesystem::exists(db + ".bak.tmp"));
}

TEST_CASE("with backups off the commit path, a commit waits for no backup and the owner's tick writes it",
          "[persistence][backup]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  auto o = test::options();
  o.backup_on_commit = false;
  auto store = test::open_ok(db, report, o);
  std::filesystem::remove(db + ".bak");  // whatever the first start left
  REQUIRE(store.commit({{"axis.x.mode", 4}}, test::kTcp));
  CHECK_FALSE(std::filesystem::exists(db + ".bak"));
  CHECK(store.backup_pending());
  REQUIRE(store.backup_if_due());
  REQUIRE(std::filesystem::exists(db + ".bak"));
  CHECK(test::sql_int(db + ".bak", "SELECT value FROM settings WHERE name='axis.x.mode'") == 4);
  CHECK_FALSE(store.backup_pending());
}

TEST_CASE("a settings write is committed while the owner's backup is being written, and the next backup holds it",
          "[persistence][backup]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  auto store = store_with_backup_due(db);
  // Before the backup was taken off the writer's lock, this write waited until the gate opened.
  const auto write = beside_a_held_backup([&] { return store.backup_if_due(); },
                                          [&] { return store.commit({{"axis.x.mode", 5}}, test::kTcp); });
  CHECK(write.answered);
  REQUIRE(write.result);
  REQUIRE(write.backed_up);
  CHECK(test::sql_int(db + ".bak", "SELECT value FROM settings WHERE name='axis.x.mode'") == 4);
  CHECK(store.backup_pending());  // the write came after the backup's snapshot
  REQUIRE(store.backup_if_due());
  CHECK(test::sql_int(db + ".bak", "SELECT value FROM settings WHERE name='axis.x.mode'") == 5);
  CHECK_FALSE(store.backup_pending());
}

TEST_CASE("the settings-lost flag is answered at once while another thread holds the store for a backup",
          "[persistence][backup]") {
  // An event loop asks for it on every cmd.reset_alarm: it must never wait
  // for whatever the store is doing on another thread.
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  auto store = store_with_backup_due(db);
  const auto asked = beside_a_held_backup([&] { return store.backup_now(); },  // holds the store's lock throughout
                                          [&] { return store.settings_lost(); });
  CHECK(asked.answered);
  CHECK_FALSE(asked.result);
  REQUIRE(asked.backed_up);
}

TEST_CASE("a checkpoint beside the writer leaves every committed setting in the database file",
          "[persistence][checkpoint]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  auto store = test::open_ok(db, report);
  for (int v = 10; v < 40; ++v) REQUIRE(store.commit({{"axis.x.mode", v}}, test::kTcp));
  REQUIRE(store.checkpoint());
  // Read straight from the database file, ignoring the WAL: the checkpoint copied it there.
  const std::string file_alone = dir.file("file-alone.db");
  std::filesystem::copy_file(db, file_alone);
  test::sql_exec(file_alone, "PRAGMA journal_mode=DELETE");  // a read-only open of a WAL file needs its -shm
  CHECK(test::sql_int(file_alone, "SELECT value FROM settings WHERE name='axis.x.mode'") == 39);
  REQUIRE(store.commit({{"axis.x.mode", 40}}, test::kTcp));
  CHECK(store.value("axis.x.mode") == 40);
}

TEST_CASE("the housekeeping of an idle store touches no file until something is written again",
          "[persistence][checkpoint]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  auto o = faulty_options();
  o.audit_max_rows = 3;
  auto store = test::open_ok(db, report, o);
  for (int v = 10; v < 16; ++v) REQUIRE(store.commit({{"axis.x.mode", v}}, test::kTcp));
  REQUIRE(store.prune_audit());
  REQUIRE(store.checkpoint());
  const long idle_from = fault_vfs::file_touches();
  for (int look = 0; look < 5; ++look) {  // the monitor's looks, twice a second
    REQUIRE(store.prune_audit());
    REQUIRE(store.checkpoint());
  }
  CHECK(fault_vfs::file_touches() == idle_from);
  // A write makes both due again: the audit log keeps its bound, the WAL is emptied into the file.
  REQUIRE(store.commit({{"axis.x.mode", 99}}, test::kTcp));
  const long written_at = fault_vfs::file_touches();
  REQUIRE(store.prune_audit());
  REQUIRE(store.checkpoint());
  CHECK(fault_vfs::file_touches() > written_at);
  CHECK(store.recent_changes(100)->size() == 3);
  const std::string file_alone = dir.file("file-alone.db");
  std::filesystem::copy_file(db, file_alone);
  test::sql_exec(file_alone, "PRAGMA journal_mode=DELETE");
  CHECK(test::sql_int(file_alone, "SELECT value FROM settings WHERE name='axis.x.mode'") == 99);
}

TEST_CASE("backups are deferred while commits come fast, and written by close", "[persistence][backup]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  auto o = test::options();
  o.backup_min_interval = std::chrono::hours(1);
  {
    auto store = test::open_ok(db, report, o);  // created: writes the first backup
    REQUIRE(store.commit({{"axis.x.mode", 4}}, test::kTcp));
    CHECK(store.backup_pending());
    CHECK(test::sql_int(db + ".bak", "SELECT value FROM settings WHERE name='axis.x.mode'") == 3);
  }
  CHECK(test::sql_int(db + ".bak", "SELECT value FROM settings WHERE name='axis.x.mode'") == 4);
}

TEST_CASE("a damaged database header is detected and the last good backup restored", "[persistence][fault]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  {
    auto store = test::open_ok(db, report);
    REQUIRE(store.commit({{"axis.x.seek_feedrate", 4321}}, test::kTcp));
  }
  test::smash(db, 0, 100);
  test::CapturedLog log;
  auto o = test::options();
  o.logger = log.logger;
  auto store = test::open_ok(db, report, o);
  CHECK(report.outcome == OpenOutcome::restored_from_backup);
  CHECK(report.restored_from == db + ".bak");
  CHECK_FALSE(report.settings_lost);
  CHECK(store.value("axis.x.seek_feedrate") == 4321);
  CHECK(std::filesystem::exists(report.damaged_copy));
  CHECK_THAT(log.text(), Catch::Contains("damaged") && Catch::Contains("restored from backup " + db + ".bak"));
  CHECK(store.check_integrity());
}

TEST_CASE("damaged pages inside the database fail the integrity check and the backup is restored",
          "[persistence][fault]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  {
    auto o = test::options();
    auto store = test::open_ok(db, report, o);
    std::vector<SettingWrite> w;
    for (int i = 0; i < 30; ++i) REQUIRE(store.commit({{"global.watchdog_ms", 600 + i}}, test::kTcp));
  }
  auto size = std::filesystem::file_size(db);
  REQUIRE(size >= 3 * 4096);
  for (std::size_t page = 1; page * 4096 < size; ++page) test::smash(db, page * 4096 + 8, 64);
  auto store = test::open_ok(db, report);
  CHECK(report.outcome == OpenOutcome::restored_from_backup);
  CHECK(store.value("global.watchdog_ms") == 629);
}

TEST_CASE("when the newest backup is damaged too, the one before is restored", "[persistence][fault]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  {
    auto store = test::open_ok(db, report);
    REQUIRE(store.commit({{"axis.y.mode", 1}}, test::kTcp));
    REQUIRE(store.commit({{"axis.y.mode", 2}}, test::kTcp));
  }
  test::smash(db, 0, 100);
  test::smash(db + ".bak", 0, 100);
  test::CapturedLog log;
  auto o = test::options();
  o.logger = log.logger;
  auto store = test::open_ok(db, report, o);
  CHECK(report.outcome == OpenOutcome::restored_from_backup);
  CHECK(report.restored_from == db + ".bak.1");
  CHECK(store.value("axis.y.mode") == 1);
  CHECK_THAT(log.text(), Catch::Contains("backup " + db + ".bak is not usable"));
}

TEST_CASE("a damaged database without a good backup starts on defaults with settings lost", "[persistence][fault]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  {
    auto store = test::open_ok(db, report);
    REQUIRE(store.commit({{"axis.x.mode", 7}}, test::kTcp));
  }
  std::filesystem::remove(db + ".bak");
  std::filesystem::remove(db + ".bak.1");
  test::smash(db, 0, 100);
  test::CapturedLog log;
  auto o = test::options();
  o.logger = log.logger;
  {
    auto store = test::open_ok(db, report, o);
    CHECK(report.outcome == OpenOutcome::defaults_settings_lost);
    CHECK(report.settings_lost);
    CHECK(store.settings_lost());
    CHECK(store.value("axis.x.mode") == 3);
    CHECK_THAT(log.text(), Catch::Contains("critical") && Catch::Contains("DEFAULT settings"));
  }
  // Still latched after a restart, until someone acknowledges it.
  {
    auto store = test::open_ok(db, report);
    CHECK(report.outcome == OpenOutcome::opened);
    CHECK(report.settings_lost);
    REQUIRE(store.acknowledge_settings_lost(test::kTcp));
    CHECK_FALSE(store.settings_lost());
    CHECK(store.recent_changes(1)->front().name == "settings_lost");
  }
  test::open_ok(db, report);
  CHECK_FALSE(report.settings_lost);
}

TEST_CASE("a database file that vanished is restored from its backup", "[persistence][fault]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  {
    auto store = test::open_ok(db, report);
    REQUIRE(store.commit({{"axis.x.mode", 2}}, test::kTcp));
  }
  std::filesystem::remove(db);
  auto store = test::open_ok(db, report);
  CHECK(report.outcome == OpenOutcome::restored_from_backup);
  CHECK(store.value("axis.x.mode") == 2);
}

TEST_CASE("a database file truncated to nothing is restored from its backup, not taken as a first start",
          "[persistence][fault]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  {
    auto store = test::open_ok(db, report);
    REQUIRE(store.commit({{"axis.x.mode", 2}}, test::kTcp));
  }
  std::filesystem::resize_file(db, 0);
  auto store = test::open_ok(db, report);
  CHECK(report.outcome == OpenOutcome::restored_from_backup);
  CHECK(store.value("axis.x.mode") == 2);
}

TEST_CASE("a first start interrupted before anything was written starts fresh", "[persistence]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  test::write_text(db, "");
  OpenReport report;
  auto store = test::open_ok(db, report);
  CHECK(report.outcome == OpenOutcome::created);
  CHECK_FALSE(report.settings_lost);
  CHECK(store.value("axis.x.mode") == 3);
}

TEST_CASE("an intact start says so in the log", "[persistence]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  test::CapturedLog log;
  auto o = test::options();
  o.logger = log.logger;
  { test::open_ok(db, report, o); }
  CHECK_THAT(log.text(), Catch::Contains("created"));
  test::open_ok(db, report, o);
  CHECK_THAT(log.text(), Catch::Contains("opened, intact"));
}
