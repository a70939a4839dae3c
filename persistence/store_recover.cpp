// How a writable open finds its database: the file as it is, the newest good
// backup when the file is missing or damaged, or an empty new one.
#include <fmt/format.h>

#include <cerrno>
#include <cstdio>
#include <optional>
#include <string>

#include "persistence/durable_files.hpp"
#include "persistence/store_impl.hpp"

namespace persistence {

namespace {

// Opens a database and configures durability: WAL + synchronous=FULL.
Result<sql::Db> open_configured(const std::string& path, bool create, const char* vfs) {
  int flags = SQLITE_OPEN_READWRITE | (create ? SQLITE_OPEN_CREATE : 0);
  auto db = sql::Db::open(path, flags, vfs);
  if (!db) return db;
  auto mode = db->prepare("PRAGMA journal_mode=WAL");
  if (!mode) return std::unexpected(mode.error());
  auto row = mode->step("switching to WAL journal mode");
  if (!row) return std::unexpected(row.error());
  if (!*row || mode->text_at(0) != "wal")
    return std::unexpected(Error{ErrorKind::io, fmt::format("{}: could not switch to WAL journal mode (got '{}'); "
                                                            "the file system may not support it",
                                                            path, *row ? mode->text_at(0) : "")});
  mode->reset();
  if (auto s = db->exec("PRAGMA synchronous=FULL", "setting synchronous=FULL"); !s) return std::unexpected(s.error());
  return db;
}

// Opens an existing database and proves it intact. Errors of kind `corrupt`
// mean "restore"; any other error is returned to the caller as is.
Result<sql::Db> open_verified(const std::string& path, const char* vfs, int& version) {
  auto db = open_configured(path, false, vfs);
  if (!db) return db;
  auto v = db->query_int("PRAGMA user_version", "reading the schema version");
  if (!v) return std::unexpected(v.error());
  version = static_cast<int>(*v);
  auto problems = db->integrity_problems();
  if (!problems) return std::unexpected(problems.error());
  if (*problems)
    return std::unexpected(Error{ErrorKind::corrupt, fmt::format("{}: integrity check failed: {}", path, **problems)});
  if (version > kSchemaVersion)
    return std::unexpected(Error{ErrorKind::version,
                                 fmt::format("{}: written by a newer firmware (schema version {}, this firmware "
                                             "knows up to {}); install that firmware or restore an exported "
                                             "settings file",
                                             path, version, kSchemaVersion)});
  return db;
}

// Leftovers of a backup or restore interrupted by a power cut.
void remove_leftovers(const std::string& path) {
  remove_quiet(bak_path(path, 0) + ".tmp");
  remove_quiet(bak_path(path, 0) + ".tmp-journal");
  remove_quiet(path + ".restore.tmp");
}

// Copies the newest usable backup over `path`; the backup used, if any.
std::optional<std::string> restore_from_backup(const std::string& path, const char* vfs, const OpenNotes& note) {
  for (int gen = 0; gen < 2; ++gen) {
    std::string candidate = bak_path(path, gen);
    if (!exists(candidate)) continue;
    if (auto problem = backup_problem(candidate, vfs)) {
      note(spdlog::level::err, fmt::format("backup {} is not usable: {}", candidate, *problem));
      continue;
    }
    remove_sidecars(path);
    if (auto s = copy_durable(candidate, path); !s) {
      note(spdlog::level::err, fmt::format("restoring {} failed: {}", candidate, s.error().message));
      continue;
    }
    return candidate;
  }
  return std::nullopt;
}

// The database replaced by the newest good backup (true), or nothing to
// restore: "settings lost" is latched and the start is a fresh one (false).
bool restore_or_lose(const std::string& path, const char* vfs, std::string_view consequence, OpenReport& report,
                     const OpenNotes& note) {
  auto used = restore_from_backup(path, vfs, note);
  if (!used) {
    report.outcome = OpenOutcome::defaults_settings_lost;
    report.settings_lost = true;
    return false;
  }
  report.outcome = OpenOutcome::restored_from_backup;
  report.restored_from = *used;
  note(spdlog::level::warn, fmt::format("settings database {} restored from backup {}{}", path, *used, consequence));
  return true;
}

// No database file: true when a backup took its place, false for a fresh start.
bool recover_missing(const std::string& path, const char* vfs, OpenReport& report, const OpenNotes& note) {
  if (!backups_exist(path)) {
    report.outcome = OpenOutcome::created;
    return false;
  }
  note(spdlog::level::err, fmt::format("settings database {} is missing but backups exist", path));
  return restore_or_lose(path, vfs, "", report, note);
}

// A damaged database: kept aside for diagnosis, then replaced by a backup
// (true) or by nothing (false: a fresh start).
Result<bool> recover_damaged(const std::string& path, const char* vfs, std::int64_t now_ms, const Error& damage,
                             OpenReport& report, const OpenNotes& note) {
  note(spdlog::level::critical, fmt::format("settings database is damaged: {}", damage.message));
  // Keep the damaged file (and its WAL) for diagnosis, out of the way.
  std::string aside = fmt::format("{}.corrupt-{}", path, now_ms);
  if (::rename(path.c_str(), aside.c_str()) != 0)
    return std::unexpected(os_error(path, "moving the damaged database aside", errno));
  if (exists(path + "-wal")) ::rename((path + "-wal").c_str(), (aside + "-wal").c_str());
  remove_sidecars(path);
  (void)fsync_path(dir_of(path), true);
  report.damaged_copy = aside;
  note(spdlog::level::warn, fmt::format("damaged database kept as {}", aside));
  return restore_or_lose(path, vfs, "; changes after that backup are lost", report, note);
}

// The existing file (or the backup restored in its place), proven intact;
// nullopt when it was damaged and nothing could replace it.
Result<std::optional<sql::Db>> open_existing(const std::string& path, const char* vfs, std::int64_t now_ms,
                                             int& version, OpenReport& report, const OpenNotes& note) {
  // Before anything opens it for writing (WAL mode is kept in the file).
  if (auto foreign = refuse_foreign(path, vfs); !foreign && foreign.error().kind == ErrorKind::invalid) {
    note(spdlog::level::critical, foreign.error().message);
    return std::unexpected(foreign.error());
  }
  auto db = open_verified(path, vfs, version);
  if (db && version == 0 && backups_exist(path)) {
    // An empty file next to backups is a lost database, not a first start.
    db = std::unexpected(Error{ErrorKind::corrupt, fmt::format("{}: the file is empty but backups exist", path)});
  }
  if (!db && db.error().kind == ErrorKind::corrupt && report.outcome != OpenOutcome::restored_from_backup) {
    auto restored = recover_damaged(path, vfs, now_ms, db.error(), report, note);
    if (!restored) return std::unexpected(restored.error());
    if (!*restored) return std::optional<sql::Db>{};
    db = open_verified(path, vfs, version);
  }
  if (!db) {
    note(spdlog::level::critical, db.error().message);
    return std::unexpected(db.error());
  }
  return std::optional<sql::Db>(std::move(*db));
}

}  // namespace

Status refuse_foreign(const std::string& path, const char* vfs) {
  auto db = sql::Db::open(path, SQLITE_OPEN_READONLY, vfs);
  if (!db) return std::unexpected(db.error());
  auto tables = db->query_int("SELECT count(*) FROM sqlite_master WHERE type IN ('table', 'view')", "listing the tables");
  if (!tables) return std::unexpected(tables.error());
  if (*tables == 0) return {};  // empty: a first start
  // homingd's since schema v1: settings(name, value).
  auto ours = db->query_int("SELECT count(*) FROM pragma_table_info('settings') WHERE name IN ('name', 'value')",
                            "looking for the settings table");
  if (!ours) return std::unexpected(ours.error());
  std::string why;
  if (*ours == 2) {
    // Another program may keep a settings(name, value) table too: homingd's
    // holds its registers' names (every one, from the first start on), and
    // from v2 on it has tables of its own beside it. Either is enough: a
    // damaged page may hide the rows.
    auto own_tables = db->query_int("SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name IN ("
                                    "'homing_runs', 'homing_axes', 'last_stop')",
                                    "looking for homingd's tables");
    if (!own_tables) return std::unexpected(own_tables.error());
    if (*own_tables > 0) return {};
    auto rows = db->query_int("SELECT count(*) FROM settings", "counting the settings");
    if (!rows) return std::unexpected(rows.error());
    auto mine = db->query_int("SELECT count(*) FROM settings WHERE name LIKE 'axis.%' OR name LIKE 'global.%' OR "
                              "name LIKE 'sequence.%'",
                              "looking for homingd's settings");
    if (!mine) return std::unexpected(mine.error());
    if (*rows == 0 || *mine > 0) return {};
    why = fmt::format("; its settings table holds {} row(s), none of them homingd's (axis.*, global.*, sequence.*)",
                      *rows);
  }
  auto names = db->prepare("SELECT name FROM sqlite_master WHERE type IN ('table', 'view') ORDER BY name LIMIT 5");
  if (!names) return std::unexpected(names.error());
  std::string listed;
  for (;;) {
    auto row = names->step("listing the tables");
    if (!row) return std::unexpected(row.error());
    if (!*row) break;
    listed += (listed.empty() ? "" : ", ") + names->text_at(0);
  }
  return fail(ErrorKind::invalid,
              fmt::format("{}: an SQLite database of another program ({} table(s): {}{}{}), not homingd's settings; "
                          "it was left untouched. Give --db the path of homingd's database, or of a new file",
                          path, *tables, listed, *tables > 5 ? ", ..." : "", why));
}

Result<FoundDatabase> open_or_recover(const std::string& path, const char* vfs, std::int64_t now_ms,
                                      OpenReport& report, const OpenNotes& note) {
  remove_leftovers(path);
  FoundDatabase found;
  found.fresh = !exists(path) && !recover_missing(path, vfs, report, note);
  if (!found.fresh) {
    auto db = open_existing(path, vfs, now_ms, found.version, report, note);
    if (!db) return std::unexpected(db.error());
    if (*db)
      found.db = std::move(**db);
    else
      found.fresh = true;
  }
  if (found.fresh) {
    remove_sidecars(path);
    auto db = open_configured(path, true, vfs);
    if (!db) {
      note(spdlog::level::critical, db.error().message);
      return std::unexpected(db.error());
    }
    found.db = std::move(*db);
    found.version = 0;
  }
  return found;
}

}  // namespace persistence
