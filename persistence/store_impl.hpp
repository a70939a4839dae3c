#pragma once
// Internal: SettingsStore's state and the steps its parts share
// (settings_store.cpp, store_open.cpp, store_recover.cpp, store_backup.cpp,
// store_history.cpp, transfer.cpp).
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <string_view>

#include "persistence/settings_store.hpp"
#include "persistence/sqlite_handle.hpp"

namespace persistence {

struct SettingsStore::Impl {
  std::string path;
  StoreOptions opt;
  std::shared_ptr<spdlog::logger> log;
  sql::Db db;
  std::map<std::string, std::int64_t> values;  // committed values of known registers
  // Read without mu: a command (reset_alarm) asks on an event loop, which
  // must not wait for a commit another thread holds mu through.
  std::atomic<bool> settings_lost{false};
  bool backup_dirty = false;
  bool backed_up_once = false;
  std::chrono::steady_clock::time_point last_backup{};
  mutable std::mutex mu;
  // sqlite3_total_changes64 of `db` when the audit log was last pruned and the
  // WAL last checkpointed whole: the monitor's housekeeping twice a second
  // skips both while nothing was written since (an idle module touches no file).
  std::int64_t pruned_at_changes = -1;
  std::atomic<std::int64_t> checkpointed_at_changes{-1};

  std::int64_t now_ms() const;
  const char* vfs() const { return opt.vfs.empty() ? nullptr : opt.vfs.c_str(); }

  // Prepared once, on the first write (statements of `db`; reset before it closes).
  std::optional<sql::Stmt> update_stmt;
  std::optional<sql::Stmt> audit_stmt;

  // The housekeeping connection (store_backup.cpp): the monitor's backups and
  // checkpoints read the database through it, holding `house_mu` and not
  // `mu`, so that no settings write waits for them (WAL: a reader and the
  // checkpointer run beside the writer). Every backup holds `house_mu`; when
  // both are held, `mu` was taken first.
  std::optional<sql::Db> house;
  bool house_closed = false;
  std::mutex house_mu;

  // Require `mu` held.
  Result<std::vector<std::vector<Change>>> commit_locked(const std::vector<BatchEntry>& entries);
  Status prepare_write_statements();
  Status backup_locked();
  Status backup_if_due_locked();
  bool backup_due_locked() const;

  // Require `house_mu` held.
  Status backup_from(sql::Db& src);
  Result<sql::Db*> house_db();
};

// The meta row that latches "settings lost" until a client acknowledges it.
inline constexpr std::string_view kLostKey = "settings_lost";

// What open() says happened: logged, and kept in the report.
struct OpenNotes {
  spdlog::logger& log;
  OpenReport& report;
  void operator()(spdlog::level::level_enum level, std::string message) const {
    log.log(level, "{}", message);
    report.messages.push_back(std::move(message));
  }
};

// A backup is good if it opens read-only, passes the integrity check and has
// a schema this firmware can migrate: nullopt, else why not (store_backup.cpp).
std::optional<std::string> backup_problem(const std::string& file, const char* vfs);

// The database a writable open goes on with (store_recover.cpp).
struct FoundDatabase {
  sql::Db db;
  int version = 0;     // schema version as found (0: new)
  bool fresh = false;  // created empty: nothing existed, or nothing could be restored
};

// Opens the database at `path` in WAL mode, proven intact; a missing or
// damaged one is restored from the newest good backup, or created empty with
// "settings lost" (report.outcome and the notes say which).
Result<FoundDatabase> open_or_recover(const std::string& path, const char* vfs, std::int64_t now_ms,
                                      OpenReport& report, const OpenNotes& note);

// An existing file that is an SQLite database of another program (tables,
// none of them homingd's settings table, whatever its user_version): refused,
// read over a read-only connection so that nothing in it (its WAL included)
// is touched. Errors reading it are returned as they are, so a damaged file
// is still restored.
Status refuse_foreign(const std::string& path, const char* vfs);

}  // namespace persistence
