#pragma once
// One homingd per settings database. Two daemons on one database (the
// service and a copy started by hand with the same --db) would each keep its
// own settings and overwrite the other's positions and clean-stop marks; an
// import into a database a daemon runs on would change settings under it.
// The lock is flock() on "<db>.lock", held for the life of the process: the
// kernel drops it when the process ends, however it ends (kill -9, a power
// cut leaves no lock behind). Readers (homingctl history, homing-settings)
// take no lock.
#include <expected>
#include <string>

namespace server {

class DatabaseLock {
 public:
  // The lock on db_path, or what holds it and what to do.
  static std::expected<DatabaseLock, std::string> take(const std::string& db_path);

  DatabaseLock(DatabaseLock&& other) noexcept;
  DatabaseLock& operator=(DatabaseLock&& other) noexcept;
  DatabaseLock(const DatabaseLock&) = delete;
  DatabaseLock& operator=(const DatabaseLock&) = delete;
  ~DatabaseLock();

 private:
  explicit DatabaseLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};

}  // namespace server
