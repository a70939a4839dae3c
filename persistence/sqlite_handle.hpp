#pragma once
// Internal: RAII wrappers for sqlite3* and sqlite3_stmt*, errors as values.
// Not part of the public API (settings_store.hpp does not include sqlite3.h).
#include <sqlite3.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "persistence/error.hpp"

namespace persistence::sql {

struct DbCloser {
  void operator()(sqlite3* db) const noexcept { sqlite3_close_v2(db); }
};
struct StmtFinalizer {
  void operator()(sqlite3_stmt* st) const noexcept { sqlite3_finalize(st); }
};

// Maps an SQLite result code (plus the OS errno behind an I/O error) to a kind.
ErrorKind classify(int rc, int system_errno);
// A technician's sentence: "<file>: <what> failed: <sqlite text>; <hint>".
Error make_error(const std::string& path, std::string_view what, int rc, int system_errno,
                 std::string_view detail);

class Stmt;

class Db {
 public:
  // flags: SQLITE_OPEN_* ; vfs: nullptr for the default VFS.
  static Result<Db> open(const std::string& path, int flags, const char* vfs = nullptr);

  sqlite3* get() const { return db_.get(); }
  const std::string& path() const { return path_; }
  explicit operator bool() const { return static_cast<bool>(db_); }
  void close() { db_.reset(); }

  Status exec(std::string_view sql, std::string_view what);
  Result<Stmt> prepare(std::string_view sql) const;
  // Runs a statement that returns one integer (e.g. PRAGMA user_version).
  Result<std::int64_t> query_int(std::string_view sql, std::string_view what) const;
  // PRAGMA integrity_check: empty optional = "ok", else the first problems reported.
  Result<std::optional<std::string>> integrity_problems() const;

  Error error(int rc, std::string_view what) const;

 private:
  std::unique_ptr<sqlite3, DbCloser> db_;
  std::string path_;
};

class Stmt {
 public:
  Stmt(const Db& db, sqlite3_stmt* st) : db_(&db), st_(st) {}

  Stmt& bind(int index, std::int64_t v);
  Stmt& bind(int index, double v);
  Stmt& bind(int index, std::string_view v);
  Stmt& bind_null(int index);
  // true: a row is available; false: done.
  Result<bool> step(std::string_view what);
  // Steps to completion (for INSERT/UPDATE/DELETE), then resets for reuse.
  Status run(std::string_view what);
  void reset();

  std::int64_t int_at(int col) const { return sqlite3_column_int64(st_.get(), col); }
  double real_at(int col) const { return sqlite3_column_double(st_.get(), col); }
  bool null_at(int col) const { return sqlite3_column_type(st_.get(), col) == SQLITE_NULL; }
  std::string text_at(int col) const;

 private:
  const Db* db_;
  std::unique_ptr<sqlite3_stmt, StmtFinalizer> st_;
  int bind_rc_ = SQLITE_OK;
};

// BEGIN IMMEDIATE ... COMMIT; rolls back in the destructor unless committed.
class Transaction {
 public:
  static Result<Transaction> begin(Db& db, std::string_view what);
  Transaction(Transaction&& o) noexcept : db_(o.db_) { o.db_ = nullptr; }
  Transaction& operator=(Transaction&&) = delete;
  ~Transaction() { rollback(); }
  Status commit(std::string_view what);
  void rollback() noexcept;

 private:
  explicit Transaction(Db& db) : db_(&db) {}
  Db* db_;
};

}  // namespace persistence::sql
