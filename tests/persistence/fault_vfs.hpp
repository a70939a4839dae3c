#pragma once
// A SQLite VFS shim ("faulty") over the default VFS that fails writes on
// demand, so tests can simulate a full or read-only disk without mounts or
// permissions (the tests run as root, where chmod does not stop writes).
//   - disk_full: xWrite/xTruncate return SQLITE_FULL (as the unix VFS does on ENOSPC)
//   - read_only: xWrite/xTruncate/xSync return SQLITE_IOERR_* with errno EROFS
#include <chrono>
#include <string>

namespace fault_vfs {

enum class Fault { none, disk_full, read_only };

inline constexpr const char* kName = "faulty";

void install();  // idempotent
// Arms a fault that starts after `writes_before` more successful writes.
void arm(Fault fault, int writes_before = 0);
void disarm();
int faults_hit();  // writes refused since the last arm()
// Reads, writes and WAL-index locks of every file opened through the VFS so
// far: a store that touches no file leaves it unchanged.
long file_touches();

// Holds every write to a backup file (a name ending in ".bak.tmp") from
// construction until release(), so a test can act while a backup is half
// written. held() waits (at most `within`) until one is held.
class BackupGate {
 public:
  BackupGate();
  ~BackupGate() { release(); }
  bool held(std::chrono::milliseconds within);
  void release();
};

struct Scoped {
  Scoped(Fault f, int writes_before = 0) { arm(f, writes_before); }
  ~Scoped() { disarm(); }
};

}  // namespace fault_vfs
