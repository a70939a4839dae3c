#pragma once
// Internal: file operations that survive a power cut (fsync of the file and
// of its directory around every rename), the store's file names, and OS
// errors as the store reports them.
#include <string>
#include <string_view>

#include "persistence/error.hpp"

namespace persistence {

// <db>.bak (generation 0, newest) and <db>.bak.1.
std::string bak_path(const std::string& db, int generation);
bool backups_exist(const std::string& db);

bool exists(const std::string& path);
void remove_quiet(const std::string& path);
// The -wal, -shm and -journal files SQLite keeps next to a database.
void remove_sidecars(const std::string& db);

// An errno as an Error whose kind says full disk, read-only or other I/O.
Error os_error(const std::string& path, std::string_view what, int err);

std::string dir_of(const std::string& path);
Status fsync_path(const std::string& path, bool directory);
// rename(2), then fsync of the target's directory.
Status rename_durable(const std::string& from, const std::string& to);
// Copies `from` to `to` through a temporary file, fsynced and renamed into place.
Status copy_durable(const std::string& from, const std::string& to);

}  // namespace persistence
