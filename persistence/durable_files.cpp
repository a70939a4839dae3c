#include "persistence/durable_files.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace fs = std::filesystem;

namespace persistence {

std::string bak_path(const std::string& db, int generation) {
  return generation == 0 ? db + ".bak" : fmt::format("{}.bak.{}", db, generation);
}

bool backups_exist(const std::string& db) { return exists(bak_path(db, 0)) || exists(bak_path(db, 1)); }

bool exists(const std::string& p) {
  std::error_code ec;
  return fs::exists(p, ec);
}

void remove_quiet(const std::string& p) {
  std::error_code ec;
  fs::remove(p, ec);
}

void remove_sidecars(const std::string& db) {
  remove_quiet(db + "-wal");
  remove_quiet(db + "-shm");
  remove_quiet(db + "-journal");
}

Error os_error(const std::string& path, std::string_view what, int err) {
  ErrorKind kind = ErrorKind::io;
  if (err == EROFS || err == EACCES || err == EPERM) kind = ErrorKind::read_only;
  if (err == ENOSPC || err == EDQUOT || err == EFBIG) kind = ErrorKind::disk_full;
  return Error{kind, fmt::format("{}: {} failed: {}", path, what, std::strerror(err))};
}

std::string dir_of(const std::string& path) {
  fs::path p = fs::absolute(fs::path(path)).parent_path();
  return p.empty() ? std::string(".") : p.string();
}

Status fsync_path(const std::string& path, bool directory) {
  int fd = ::open(path.c_str(), (directory ? O_DIRECTORY : 0) | O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::unexpected(os_error(path, "opening for fsync", errno));
  int rc = ::fsync(fd);
  int err = errno;
  ::close(fd);
  if (rc != 0) return std::unexpected(os_error(path, "fsync", err));
  return {};
}

Status rename_durable(const std::string& from, const std::string& to) {
  if (::rename(from.c_str(), to.c_str()) != 0)
    return std::unexpected(os_error(from, fmt::format("renaming to {}", to), errno));
  return fsync_path(dir_of(to), true);
}

Status copy_durable(const std::string& from, const std::string& to) {
  std::string tmp = to + ".restore.tmp";
  std::error_code ec;
  fs::copy_file(from, tmp, fs::copy_options::overwrite_existing, ec);
  if (ec) return std::unexpected(os_error(tmp, fmt::format("copying {}", from), ec.value()));
  if (auto s = fsync_path(tmp, false); !s) return s;
  return rename_durable(tmp, to);
}

}  // namespace persistence
