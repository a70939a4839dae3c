#pragma once
// Internal: SettingsStore's state, shared by settings_store.cpp and transfer.cpp.
#include <chrono>
#include <mutex>

#include "persistence/settings_store.hpp"
#include "persistence/sqlite_handle.hpp"

namespace persistence {

struct SettingsStore::Impl {
  std::string path;
  StoreOptions opt;
  std::shared_ptr<spdlog::logger> log;
  sql::Db db;
  std::map<std::string, std::int64_t> values;  // committed values of known registers
  bool settings_lost = false;
  bool backup_dirty = false;
  bool backed_up_once = false;
  std::chrono::steady_clock::time_point last_backup{};
  mutable std::mutex mu;

  std::int64_t now_ms() const;
  const char* vfs() const { return opt.vfs.empty() ? nullptr : opt.vfs.c_str(); }

  // Both require `mu` held.
  Result<std::vector<Change>> commit_locked(const std::vector<SettingWrite>& writes, const ChangeSource& source);
  Status backup_locked();
  Status backup_if_due_locked();
};

}  // namespace persistence
