#include "fault_vfs.hpp"

#include <sqlite3.h>

#include <atomic>
#include <condition_variable>
#include <string_view>
#include <cerrno>
#include <cstring>
#include <mutex>

#include "vfs_passthrough.hpp"

namespace fault_vfs {
namespace {

std::atomic<Fault> g_fault{Fault::none};
std::atomic<int> g_countdown{0};
std::atomic<int> g_hits{0};
std::atomic<long> g_touches{0};
std::atomic<int> g_errno{0};
sqlite3_vfs* g_real = nullptr;
sqlite3_vfs g_vfs{};

struct File {
  sqlite3_file base;
  sqlite3_file* real;
  bool backup;  // the temporary file a backup is written to
};

std::mutex g_gate_mu;
std::condition_variable g_gate_cv;
bool g_gate_closed = false;
bool g_gate_holding = false;

void pass_gate(sqlite3_file* f) {
  if (!reinterpret_cast<File*>(f)->backup) return;
  std::unique_lock lock(g_gate_mu);
  if (!g_gate_closed) return;
  g_gate_holding = true;
  g_gate_cv.notify_all();
  g_gate_cv.wait(lock, [] { return !g_gate_closed; });
}
sqlite3_file* R(sqlite3_file* f) { return reinterpret_cast<File*>(f)->real; }

// Returns the error code to inject, or SQLITE_OK.
int should_fail(int readonly_code) {
  Fault f = g_fault.load();
  if (f == Fault::none) return SQLITE_OK;
  if (g_countdown.fetch_sub(1) > 0) return SQLITE_OK;
  ++g_hits;
  if (f == Fault::disk_full) {
    g_errno = ENOSPC;
    return SQLITE_FULL;
  }
  g_errno = EROFS;
  return readonly_code;
}

int x_close(sqlite3_file* f) {
  int rc = R(f)->pMethods ? R(f)->pMethods->xClose(R(f)) : SQLITE_OK;
  return rc;
}
int x_read(sqlite3_file* f, void* b, int n, sqlite3_int64 o) {
  ++g_touches;
  return R(f)->pMethods->xRead(R(f), b, n, o);
}
int x_write(sqlite3_file* f, const void* b, int n, sqlite3_int64 o) {
  ++g_touches;
  pass_gate(f);
  if (int rc = should_fail(SQLITE_IOERR_WRITE)) return rc;
  return R(f)->pMethods->xWrite(R(f), b, n, o);
}
int x_truncate(sqlite3_file* f, sqlite3_int64 s) {
  if (int rc = should_fail(SQLITE_IOERR_TRUNCATE)) return rc == SQLITE_FULL ? SQLITE_IOERR_TRUNCATE : rc;
  return R(f)->pMethods->xTruncate(R(f), s);
}
int x_sync(sqlite3_file* f, int flags) {
  if (g_fault.load() == Fault::read_only) {
    if (int rc = should_fail(SQLITE_IOERR_FSYNC)) return rc;
  }
  return R(f)->pMethods->xSync(R(f), flags);
}
int x_fcntl(sqlite3_file* f, int op, void* a) {
  if (op == SQLITE_FCNTL_LAST_ERRNO && g_errno.load() != 0) {
    *static_cast<int*>(a) = g_errno.load();
    return SQLITE_OK;
  }
  return vfs_passthrough::FileMethods<R>::fcntl(f, op, a);
}

// A lock on the WAL index: every transaction, read or write, and every checkpoint takes some.
int x_shmlock(sqlite3_file* f, int offset, int n, int flags) {
  ++g_touches;
  return R(f)->pMethods->xShmLock(R(f), offset, n, flags);
}

const sqlite3_io_methods kMethods = [] {
  sqlite3_io_methods m = vfs_passthrough::FileMethods<R>::with(x_close, x_read, x_write, x_truncate, x_sync, x_fcntl);
  m.xShmLock = x_shmlock;
  return m;
}();

int x_open(sqlite3_vfs*, sqlite3_filename name, sqlite3_file* f, int flags, int* out_flags) {
  auto* file = reinterpret_cast<File*>(f);
  file->real = reinterpret_cast<sqlite3_file*>(file + 1);
  const std::string_view n = name ? std::string_view(name) : std::string_view();
  file->backup = n.size() >= 8 && n.substr(n.size() - 8) == ".bak.tmp";
  std::memset(file->real, 0, static_cast<std::size_t>(g_real->szOsFile));
  int rc = g_real->xOpen(g_real, name, file->real, flags, out_flags);
  file->base.pMethods = file->real->pMethods ? &kMethods : nullptr;
  return rc;
}
int x_delete(sqlite3_vfs*, const char* n, int sync) { return g_real->xDelete(g_real, n, sync); }
int x_lasterror(sqlite3_vfs* v, int n, char* m) {
  if (int e = g_errno.load()) return e;
  return vfs_passthrough::last_error(v, n, m);
}

}  // namespace

void install() {
  static std::once_flag once;
  std::call_once(once, [] {
    g_real = sqlite3_vfs_find(nullptr);
    vfs_passthrough::fill(g_vfs, kName, static_cast<int>(sizeof(File)));
    g_vfs.xOpen = x_open;
    g_vfs.xDelete = x_delete;
    g_vfs.xGetLastError = x_lasterror;
    sqlite3_vfs_register(&g_vfs, 0);
  });
}

void arm(Fault fault, int writes_before) {
  g_countdown = writes_before;
  g_hits = 0;
  g_errno = 0;
  g_fault = fault;
}

void disarm() {
  g_fault = Fault::none;
  g_errno = 0;
}

int faults_hit() { return g_hits.load(); }

long file_touches() { return g_touches.load(); }

BackupGate::BackupGate() {
  std::lock_guard lock(g_gate_mu);
  g_gate_closed = true;
  g_gate_holding = false;
}

bool BackupGate::held(std::chrono::milliseconds within) {
  std::unique_lock lock(g_gate_mu);
  return g_gate_cv.wait_for(lock, within, [] { return g_gate_holding; });
}

void BackupGate::release() {
  std::lock_guard lock(g_gate_mu);
  g_gate_closed = false;
  g_gate_cv.notify_all();
}

}  // namespace fault_vfs
