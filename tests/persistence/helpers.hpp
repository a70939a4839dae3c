#pragma once
// Persistence test helpers: loggers, register defaults, direct SQL; temporary
// directories and files from the shared test support (tests/support).
#include <spdlog/sinks/null_sink.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "persistence/settings_store.hpp"
#include "tests/support/temp_dir.hpp"

namespace test {

using test_support::TempDir;
using test_support::write_text;

inline std::shared_ptr<spdlog::logger> quiet_logger() {
  static auto l = std::make_shared<spdlog::logger>("persistence-test", std::make_shared<spdlog::sinks::null_sink_mt>());
  return l;
}

struct CapturedLog {
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> sink = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(200);
  std::shared_ptr<spdlog::logger> logger = std::make_shared<spdlog::logger>("capture", sink);
  CapturedLog() { sink->set_pattern("%l %v"); }
  std::string text() const {
    std::string all;
    for (const auto& line : sink->last_formatted()) all += line;
    return all;
  }
};

inline std::vector<persistence::SettingDefault> defaults() {
  return {
      {"axis.x.mode", 3},
      {"axis.x.seek_feedrate", 3000},
      {"axis.x.home_position", -1500},
      {"axis.y.mode", 0},
      {"global.watchdog_ms", 500},
  };
}

inline persistence::StoreOptions options() {
  persistence::StoreOptions o;
  o.logger = quiet_logger();
  o.backup_min_interval = std::chrono::milliseconds(0);
  return o;
}

inline const persistence::ChangeSource kTcp{"tcp", "192.168.0.20:50122"};
inline const persistence::ChangeSource kRtu{"rtu", "unit 5"};

// Opens or fails the test with the store's own message.
inline persistence::SettingsStore open_ok(const std::string& path, persistence::OpenReport& report,
                                          persistence::StoreOptions o = options(),
                                          const std::vector<persistence::SettingDefault>& d = defaults()) {
  auto s = persistence::SettingsStore::open(path, d, report, std::move(o));
  if (!s) throw std::runtime_error("open failed: " + s.error().message);
  return std::move(*s);
}

// Runs SQL on a database file directly (to build old schemas, inspect rows).
inline void sql_exec(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  if (sqlite3_open(path.c_str(), &db) != SQLITE_OK) {
    sqlite3_close(db);
    throw std::runtime_error("cannot open " + path);
  }
  char* err = nullptr;
  int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err);
  std::string msg = err ? err : "";
  sqlite3_free(err);
  sqlite3_close(db);
  if (rc != SQLITE_OK) throw std::runtime_error("sql failed: " + msg);
}

inline long long sql_int(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  sqlite3_stmt* st = nullptr;
  long long v = -1;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &st, nullptr) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
    v = sqlite3_column_int64(st, 0);
  sqlite3_finalize(st);
  sqlite3_close(db);
  return v;
}

// Overwrites `n` bytes at `offset` with garbage.
inline void smash(const std::string& path, std::size_t offset, std::size_t n) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(offset));
  std::string junk(n, '\0');
  for (std::size_t i = 0; i < n; ++i) junk[i] = static_cast<char>(0xA5 ^ (i * 31));
  f.write(junk.data(), static_cast<std::streamsize>(n));
}

}  // namespace test
