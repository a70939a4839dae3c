#include "persistence/sqlite_handle.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include <sys/statvfs.h>

namespace persistence {

std::string_view kind_name(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::io: return "io";
    case ErrorKind::disk_full: return "disk_full";
    case ErrorKind::read_only: return "read_only";
    case ErrorKind::corrupt: return "corrupt";
    case ErrorKind::busy: return "busy";
    case ErrorKind::invalid: return "invalid";
    case ErrorKind::version: return "version";
    case ErrorKind::internal: return "internal";
  }
  return "?";
}

}  // namespace persistence

namespace persistence::sql {

ErrorKind classify(int rc, int system_errno) {
  switch (rc & 0xff) {
    case SQLITE_FULL: return ErrorKind::disk_full;
    case SQLITE_READONLY: return ErrorKind::read_only;
    case SQLITE_PERM: return ErrorKind::read_only;
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB: return ErrorKind::corrupt;
    case SQLITE_BUSY:
    case SQLITE_LOCKED: return ErrorKind::busy;
    case SQLITE_IOERR:
    case SQLITE_CANTOPEN:
      switch (system_errno) {
        case EROFS:
        case EACCES:
        case EPERM: return ErrorKind::read_only;
        case ENOSPC:
        case EDQUOT:
        case EFBIG: return ErrorKind::disk_full;
        default: return ErrorKind::io;
      }
    case SQLITE_MISUSE:
    case SQLITE_RANGE:
    case SQLITE_ERROR: return ErrorKind::internal;
    default: return ErrorKind::io;
  }
}

namespace {
std::string_view hint(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::disk_full:
      return "free space on the storage device";
    case ErrorKind::read_only:
      return "the storage is read-only or write-protected; check the mount and file permissions";
    case ErrorKind::corrupt:
      return "the database is damaged; the module restores its last good backup when it starts";
    case ErrorKind::busy: return "another program holds the database locked; close it and retry";
    case ErrorKind::io: return "the storage device reported an error; check it and retry";
    default: return "";
  }
}
}  // namespace

Error make_error(const std::string& path, std::string_view what, int rc, int system_errno,
                 std::string_view detail) {
  ErrorKind kind = classify(rc, system_errno);
  std::string msg = fmt::format("{}: {} failed: {}", path, what, detail);
  if (system_errno != 0 && ((rc & 0xff) == SQLITE_IOERR || (rc & 0xff) == SQLITE_CANTOPEN ||
                            (rc & 0xff) == SQLITE_FULL)) {
    msg += fmt::format(" (OS: {})", std::strerror(system_errno));
  }
  if (system_errno == ENOENT)
    msg += "; check that the file and its directory exist";
  else if (auto h = hint(kind); !h.empty())
    msg += fmt::format("; {}", h);
  return Error{kind, std::move(msg)};
}

Result<Db> Db::open(const std::string& path, int flags, const char* vfs) {
  sqlite3* raw = nullptr;
  int rc = sqlite3_open_v2(path.c_str(), &raw, flags | SQLITE_OPEN_NOMUTEX, vfs);
  Db db;
  db.db_.reset(raw);  // closed on every path, also on failure
  db.path_ = path;
  if (rc != SQLITE_OK) {
    int sys = raw ? sqlite3_system_errno(raw) : 0;
    std::string detail = raw ? sqlite3_errmsg(raw) : sqlite3_errstr(rc);
    return std::unexpected(make_error(path, "opening the database", rc, sys, detail));
  }
  sqlite3_extended_result_codes(raw, 1);
  sqlite3_busy_timeout(raw, 2000);
  return db;
}

namespace {
// For an I/O error during COMMIT SQLite often keeps no errno (sqlite3_system_errno
// is 0, and the failing write may be to the WAL file), so ask the main file's VFS,
// then the file system itself: read-only mount or no free blocks.
int diagnose_errno(sqlite3* db, const std::string& path) {
  int e = 0;
  if (sqlite3_file_control(db, "main", SQLITE_FCNTL_LAST_ERRNO, &e) == SQLITE_OK && e != 0) return e;
  std::filesystem::path dir = std::filesystem::absolute(std::filesystem::path(path)).parent_path();
  struct statvfs st {};
  if (::statvfs(dir.c_str(), &st) != 0) return 0;
  if (st.f_flag & ST_RDONLY) return EROFS;
  if (st.f_bavail == 0) return ENOSPC;
  return 0;
}
}  // namespace

Error Db::error(int rc, std::string_view what) const {
  if (!db_) return Error{ErrorKind::internal, fmt::format("{}: {} on a closed database", path_, what)};
  int sys = sqlite3_system_errno(db_.get());
  if (sys == 0 && ((rc & 0xff) == SQLITE_IOERR || (rc & 0xff) == SQLITE_CANTOPEN || (rc & 0xff) == SQLITE_FULL))
    sys = diagnose_errno(db_.get(), path_);
  return make_error(path_, what, rc, sys, sqlite3_errmsg(db_.get()));
}

Status Db::exec(std::string_view sql, std::string_view what) {
  std::string text(sql);
  char* err = nullptr;
  int rc = sqlite3_exec(db_.get(), text.c_str(), nullptr, nullptr, &err);
  std::unique_ptr<char, decltype(&sqlite3_free)> guard(err, &sqlite3_free);
  if (rc != SQLITE_OK) return std::unexpected(error(rc, what));
  return {};
}

Result<Stmt> Db::prepare(std::string_view sql) const {
  sqlite3_stmt* st = nullptr;
  int rc = sqlite3_prepare_v2(db_.get(), sql.data(), static_cast<int>(sql.size()), &st, nullptr);
  if (rc != SQLITE_OK) {
    sqlite3_finalize(st);
    return std::unexpected(error(rc, fmt::format("preparing \"{}\"", sql)));
  }
  return Stmt(*this, st);
}

Result<std::int64_t> Db::query_int(std::string_view sql, std::string_view what) const {
  auto st = prepare(sql);
  if (!st) return std::unexpected(st.error());
  auto row = st->step(what);
  if (!row) return std::unexpected(row.error());
  if (!*row) return std::int64_t{0};
  return st->int_at(0);
}

Result<std::optional<std::string>> Db::integrity_problems() const {
  auto st = prepare("PRAGMA integrity_check(20)");
  if (!st) return std::unexpected(st.error());
  std::string problems;
  for (;;) {
    auto row = st->step("checking database integrity");
    if (!row) return std::unexpected(row.error());
    if (!*row) break;
    std::string line = st->text_at(0);
    if (line == "ok") continue;
    if (!problems.empty()) problems += "; ";
    problems += line;
  }
  if (problems.empty()) return std::optional<std::string>{};
  return std::optional<std::string>{problems};
}

Stmt& Stmt::bind(int index, std::int64_t v) {
  if (bind_rc_ == SQLITE_OK) bind_rc_ = sqlite3_bind_int64(st_.get(), index, v);
  return *this;
}
Stmt& Stmt::bind(int index, double v) {
  if (bind_rc_ == SQLITE_OK) bind_rc_ = sqlite3_bind_double(st_.get(), index, v);
  return *this;
}
Stmt& Stmt::bind(int index, std::string_view v) {
  if (bind_rc_ == SQLITE_OK)
    bind_rc_ = sqlite3_bind_text(st_.get(), index, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
  return *this;
}
Stmt& Stmt::bind_null(int index) {
  if (bind_rc_ == SQLITE_OK) bind_rc_ = sqlite3_bind_null(st_.get(), index);
  return *this;
}

Result<bool> Stmt::step(std::string_view what) {
  if (bind_rc_ != SQLITE_OK) return std::unexpected(db_->error(bind_rc_, what));
  int rc = sqlite3_step(st_.get());
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  return std::unexpected(db_->error(rc, what));
}

Status Stmt::run(std::string_view what) {
  for (;;) {
    auto r = step(what);
    if (!r) {
      reset();
      return std::unexpected(r.error());
    }
    if (!*r) break;
  }
  reset();
  return {};
}

void Stmt::reset() {
  sqlite3_reset(st_.get());
  sqlite3_clear_bindings(st_.get());
  bind_rc_ = SQLITE_OK;
}

std::string Stmt::text_at(int col) const {
  const unsigned char* p = sqlite3_column_text(st_.get(), col);
  if (!p) return {};
  return std::string(reinterpret_cast<const char*>(p), static_cast<std::size_t>(sqlite3_column_bytes(st_.get(), col)));
}

Result<Transaction> Transaction::begin(Db& db, std::string_view what) {
  if (auto s = db.exec("BEGIN IMMEDIATE", what); !s) return std::unexpected(s.error());
  return Transaction(db);
}

Status Transaction::commit(std::string_view what) {
  if (!db_) return std::unexpected(Error{ErrorKind::internal, "commit of a finished transaction"});
  auto s = db_->exec("COMMIT", what);
  if (!s) {
    rollback();
    return s;
  }
  db_ = nullptr;
  return {};
}

void Transaction::rollback() noexcept {
  if (!db_) return;
  // After some I/O errors SQLite has already rolled back by itself.
  if (db_->get() && !sqlite3_get_autocommit(db_->get())) {
    sqlite3_exec(db_->get(), "ROLLBACK", nullptr, nullptr, nullptr);
  }
  db_ = nullptr;
}

}  // namespace persistence::sql
