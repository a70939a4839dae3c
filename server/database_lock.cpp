#include "database_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>
#include <utility>

namespace server {
namespace {

// The process id the holder wrote into the lock file, or "" if none is readable.
std::string holder_of(int fd) {
  char text[32] = {};
  const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
  if (n <= 0) return {};
  std::string pid(text, static_cast<std::size_t>(n));
  while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
  return pid;
}

}  // namespace

std::expected<DatabaseLock, std::string> DatabaseLock::take(const std::string& db_path) {
  // The lock belongs to the file SQLite opens: through a symbolic link (or
  // another spelling of the path) it is the same database and the same lock.
  std::error_code ec;
  const std::filesystem::path real = std::filesystem::weakly_canonical(db_path, ec);
  const std::string path = (ec ? db_path : real.string()) + ".lock";
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int err = errno;
    return std::unexpected("--db " + db_path + ": cannot open its lock file " + path + ": " + std::strerror(err) +
                           "; check that the directory exists and homingd may write there");
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    const std::string pid = holder_of(fd);
    ::close(fd);
    if (err == EWOULDBLOCK)
      return std::unexpected("--db " + db_path + ": another homingd uses this database" +
                             (pid.empty() ? std::string() : " (pid " + pid + ")") +
                             "; stop it first (systemctl stop homingd), or give this one its own --db");
    return std::unexpected("--db " + db_path + ": cannot lock " + path + ": " + std::strerror(err));
  }
  // For the message a second start gives; the lock itself is the flock, and
  // holds without the pid.
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd, 0) == 0) (void)!::pwrite(fd, pid.data(), pid.size(), 0);
  return DatabaseLock(fd);
}

DatabaseLock::DatabaseLock(DatabaseLock&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}

DatabaseLock& DatabaseLock::operator=(DatabaseLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

DatabaseLock::~DatabaseLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the descriptor releases the flock
}

}  // namespace server
