#pragma once
// A SQLite VFS shim ("faulty") over the default VFS that fails writes on
// demand, so tests can simulate a full or read-only disk without mounts or
// permissions (the tests run as root, where chmod does not stop writes).
//   - disk_full: xWrite/xTruncate return SQLITE_FULL (as the unix VFS does on ENOSPC)
//   - read_only: xWrite/xTruncate/xSync return SQLITE_IOERR_* with errno EROFS
#include <string>

namespace fault_vfs {

enum class Fault { none, disk_full, read_only };

inline constexpr const char* kName = "faulty";

void install();  // idempotent
// Arms a fault that starts after `writes_before` more successful writes.
void arm(Fault fault, int writes_before = 0);
void disarm();
int faults_hit();  // writes refused since the last arm()

struct Scoped {
  Scoped(Fault f, int writes_before = 0) { arm(f, writes_before); }
  ~Scoped() { disarm(); }
};

}  // namespace fault_vfs
