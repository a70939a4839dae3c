// The floor of a durable settings write: one row updated and committed in
// SQLite with journal_mode=WAL and synchronous=FULL (homingd's settings
// store's configuration), timed commit by commit.
//
//   sqlite_commit --db /tmp/x.db --commits 200
//
// Steady state first: --warmup commits grow the WAL file, then a checkpoint
// restarts it, so the timed commits rewrite a WAL of constant size as a
// long-running database does (a growing file makes every fsync also commit
// the file system's journal, which is not what a running daemon pays).
//
// Prints "RESULT commits=... p50_us=... p99_us=... p999_us=... max_us=... per_s=..." (per_s:
// commits per second of commit time, one commit per write) and the timed
// commits' own counters (bench::SelfCounters: CPU user and system, context
// switches, run-queue wait), the reference for homingd's durable write.
#include <sqlite3.h>

#include <cstdio>

#include "bench_util.hpp"

namespace {
void check(int rc, sqlite3* db, const char* what) {
  if (rc != SQLITE_OK && rc != SQLITE_DONE && rc != SQLITE_ROW) {
    std::fprintf(stderr, "sqlite_commit: %s: %s\n", what, sqlite3_errmsg(db));
    std::exit(1);
  }
}
}  // namespace

int main(int argc, char** argv) {
  bench::Args a(argc, argv, {{"db", "sqlite_commit.db"}, {"commits", "200"}, {"duration", "0"}, {"warmup", "300"}});
  sqlite3* db = nullptr;
  check(sqlite3_open(a.str("db").c_str(), &db), db, "open");
  check(sqlite3_exec(db, "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL;"
                         "CREATE TABLE IF NOT EXISTS settings(name TEXT PRIMARY KEY, value INTEGER NOT NULL);"
                         "INSERT OR IGNORE INTO settings VALUES('axis.x.pull_off', 1000);",
                     nullptr, nullptr, nullptr),
        db, "schema");
  sqlite3_stmt* upd = nullptr;
  check(sqlite3_prepare_v2(db, "UPDATE settings SET value = ? WHERE name = 'axis.x.pull_off'", -1, &upd, nullptr), db,
        "prepare");
  for (long i = 0; i < a.num("warmup"); ++i) {
    check(sqlite3_exec(db, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr), db, "begin");
    sqlite3_bind_int64(upd, 1, 2000 + (i & 1));
    check(sqlite3_step(upd), db, "update");
    sqlite3_reset(upd);
    check(sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr), db, "commit");
  }
  check(sqlite3_exec(db, "PRAGMA wal_checkpoint(RESTART)", nullptr, nullptr, nullptr), db, "checkpoint");
  const long n = a.num("commits");
  const double duration = a.real("duration");
  const std::int64_t end = duration > 0 ? bench::now_ns() + static_cast<std::int64_t>(duration * 1e9) : INT64_MAX;
  std::vector<double> us;
  const bench::SelfCounters before = bench::SelfCounters::now();
  for (long i = 0; (duration > 0 || i < n) && bench::now_ns() < end; ++i) {
    const std::int64_t t0 = bench::now_ns();
    check(sqlite3_exec(db, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr), db, "begin");
    sqlite3_bind_int64(upd, 1, 1000 + (i & 1));
    check(sqlite3_step(upd), db, "update");
    sqlite3_reset(upd);
    check(sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr), db, "commit");
    us.push_back((bench::now_ns() - t0) / 1000.0);
  }
  const std::string counters = bench::SelfCounters::now().since(before);
  sqlite3_finalize(upd);
  sqlite3_close(db);
  double total_us = 0;
  for (const double u : us) total_us += u;
  const double per_s = total_us > 0 ? static_cast<double>(us.size()) / (total_us / 1e6) : 0;
  const double mx = us.empty() ? 0 : *std::max_element(us.begin(), us.end());
  const double p50 = bench::percentile(us, 0.5), p99 = bench::percentile(us, 0.99), p999 = bench::percentile(us, 0.999);
  std::printf("sqlite_commit: %zu commits (WAL, synchronous=FULL): p50 %.0f us p99 %.0f us p99.9 %.0f us max %.0f us\n",
              us.size(), p50, p99, p999, mx);
  std::printf("RESULT commits=%zu p50_us=%.1f p99_us=%.1f p999_us=%.1f max_us=%.1f per_s=%.1f%s\n", us.size(), p50,
              p99, p999, mx, per_s, counters.c_str());
  return 0;
}
