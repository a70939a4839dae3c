// Backups: <db>.bak (newest, verified before it replaces the old one) and
// <db>.bak.1, written from the live database page by page.
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <memory>

#include "persistence/durable_files.hpp"
#include "persistence/store_impl.hpp"

namespace persistence {

std::optional<std::string> backup_problem(const std::string& file, const char* vfs) {
  auto db = sql::Db::open(file, SQLITE_OPEN_READONLY, vfs);
  if (!db) return db.error().message;
  auto v = db->query_int("PRAGMA user_version", "reading the schema version");
  if (!v) return v.error().message;
  if (*v < 1 || *v > kSchemaVersion) return fmt::format("{}: unusable schema version {}", file, *v);
  auto problems = db->integrity_problems();
  if (!problems) return problems.error().message;
  if (*problems) return fmt::format("{}: integrity check failed: {}", file, **problems);
  return std::nullopt;
}

namespace {
struct BackupFinisher {
  void operator()(sqlite3_backup* b) const noexcept { sqlite3_backup_finish(b); }
};

// Copies the live database (including what is still in the WAL) page by page
// into `tmp`, unsynced; the caller verifies and fsyncs it once. Then marks the
// copy as a rollback-journal database (header bytes 18-19 = 1, what
// "PRAGMA journal_mode=DELETE" writes) so it opens without -wal/-shm files.
Status copy_pages(sql::Db& src, const std::string& tmp, const char* vfs) {
  auto dst = sql::Db::open(tmp, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, vfs);
  if (!dst) return std::unexpected(dst.error());
  if (auto s = dst->exec("PRAGMA journal_mode=OFF; PRAGMA synchronous=OFF", "preparing the backup file"); !s) return s;
  std::unique_ptr<sqlite3_backup, BackupFinisher> b(sqlite3_backup_init(dst->get(), "main", src.get(), "main"));
  if (!b) return std::unexpected(dst->error(sqlite3_errcode(dst->get()), "starting the backup"));
  int rc = sqlite3_backup_step(b.get(), -1);
  int finish = sqlite3_backup_finish(b.release());
  if (rc != SQLITE_DONE) return std::unexpected(dst->error(rc, "copying the database into the backup"));
  if (finish != SQLITE_OK) return std::unexpected(dst->error(finish, "finishing the backup"));
  dst->close();
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) return std::unexpected(os_error(tmp, "opening the backup", errno));
  const unsigned char rollback_mode[2] = {1, 1};
  ssize_t n = ::pwrite(fd, rollback_mode, 2, 18);
  int err = errno;
  ::close(fd);
  if (n != 2) return std::unexpected(os_error(tmp, "writing the backup header", n < 0 ? err : EIO));
  return {};
}
}  // namespace

// Copies `src` into <db>.bak.tmp, verifies and syncs it, rotates the
// previous backup to .bak.1 and renames the new one in place.
Status SettingsStore::Impl::backup_from(sql::Db& src) {
  const std::string bak = bak_path(path, 0);
  const std::string tmp = bak + ".tmp";
  remove_quiet(tmp);
  remove_quiet(tmp + "-journal");
  if (auto s = copy_pages(src, tmp, vfs()); !s) {
    remove_quiet(tmp);
    s.error().message = fmt::format("backup {} not written: {}", bak, s.error().message);
    return s;
  }
  if (auto problem = backup_problem(tmp, vfs())) {
    remove_quiet(tmp);
    return fail(ErrorKind::io, fmt::format("backup {} failed verification: {}", tmp, *problem));
  }
  if (auto s = fsync_path(tmp, false); !s) {
    remove_quiet(tmp);
    return s;
  }
  if (exists(bak)) {
    if (::rename(bak.c_str(), bak_path(path, 1).c_str()) != 0) {
      int err = errno;
      remove_quiet(tmp);
      return std::unexpected(os_error(bak, "rotating the previous backup", err));
    }
  }
  if (auto s = rename_durable(tmp, bak); !s) {
    remove_quiet(tmp);
    return s;
  }
  log->debug("settings database {}: backup {} written", path, bak);
  return {};
}

Status SettingsStore::Impl::backup_locked() {
  std::lock_guard house_lock(house_mu);
  if (auto s = backup_from(db); !s) return s;
  backup_dirty = false;
  backed_up_once = true;
  last_backup = std::chrono::steady_clock::now();
  return {};
}

bool SettingsStore::Impl::backup_due_locked() const {
  if (!backup_dirty || !db || opt.read_only) return false;
  return !backed_up_once || std::chrono::steady_clock::now() - last_backup >= opt.backup_min_interval;
}

Status SettingsStore::Impl::backup_if_due_locked() {
  if (!backup_due_locked()) return {};
  return backup_locked();
}

Result<sql::Db*> SettingsStore::Impl::house_db() {
  if (house_closed) return fail(ErrorKind::internal, fmt::format("{}: the settings store is closed", path));
  if (!house) {
    auto opened = sql::Db::open(path, SQLITE_OPEN_READWRITE, vfs());
    if (!opened) return std::unexpected(opened.error());
    // A checkpoint that finds the writer's lock gives up at once (PASSIVE);
    // this only bounds a read that meets a WAL being restarted.
    if (auto s = opened->exec("PRAGMA busy_timeout=1000", "setting the housekeeping connection's busy timeout"); !s)
      return std::unexpected(s.error());
    // A connection reads the database (and finds its WAL) on its first
    // statement: before it, a checkpoint through it does nothing.
    if (auto n = opened->query_int("SELECT count(*) FROM sqlite_master", "reading the schema"); !n)
      return std::unexpected(n.error());
    house.emplace(std::move(*opened));
  }
  return &*house;
}

// The monitor's backup: decided under `mu`, copied without it from a read
// snapshot of the housekeeping connection, so settings writes go on
// meanwhile; one committed after the snapshot makes the next backup due.
Status SettingsStore::backup_if_due() {
  auto& m = *impl_;
  {
    std::lock_guard lock(m.mu);
    if (!m.backup_due_locked()) return {};
    m.backup_dirty = false;
  }
  Status written;
  {
    std::lock_guard house_lock(m.house_mu);
    auto src = m.house_db();
    written = src ? m.backup_from(**src) : Status(std::unexpected(src.error()));
  }
  std::lock_guard lock(m.mu);
  if (!written) {
    m.backup_dirty = true;
    return written;
  }
  m.backed_up_once = true;
  m.last_backup = std::chrono::steady_clock::now();
  return {};
}

Status SettingsStore::backup_now() {
  std::lock_guard lock(impl_->mu);
  if (!impl_->db) return fail(ErrorKind::internal, "backup of a closed settings store");
  return impl_->backup_locked();
}

// Copies the WAL's committed pages into the database file (PASSIVE: never
// waits for the writer or a reader), so that the writer's own automatic
// checkpoint, which a write would wait for, finds little or nothing left.
Status SettingsStore::checkpoint() {
  auto& m = *impl_;
  if (m.opt.read_only) return {};
  std::int64_t changes = 0;
  {
    std::lock_guard lock(m.mu);
    if (!m.db) return {};
    changes = sqlite3_total_changes64(m.db.get());
  }
  if (changes == m.checkpointed_at_changes) return {};  // the WAL holds nothing new since the last whole one
  std::lock_guard house_lock(m.house_mu);
  auto db = m.house_db();
  if (!db) return std::unexpected(db.error());
  int log_frames = -1;
  int checkpointed_frames = -1;
  int rc = sqlite3_wal_checkpoint_v2((*db)->get(), "main", SQLITE_CHECKPOINT_PASSIVE, &log_frames, &checkpointed_frames);
  if (rc != SQLITE_OK && rc != SQLITE_BUSY) return std::unexpected((*db)->error(rc, "checkpointing the WAL"));
  // Whole: every frame of the WAL is in the database file (a reader or the
  // writer may hold some back: tried again at the next look).
  if (rc == SQLITE_OK && log_frames >= 0 && checkpointed_frames == log_frames) m.checkpointed_at_changes = changes;
  return {};
}

bool SettingsStore::backup_pending() const {
  std::lock_guard lock(impl_->mu);
  return impl_->backup_dirty;
}

}  // namespace persistence
