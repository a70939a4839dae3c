#pragma once
// What the test VFS shims (fault_vfs, power_cut_vfs) hand on unchanged to
// the default VFS: everything but opening and deleting files. A shim fills
// its sqlite3_vfs with these, then sets its own xOpen, xDelete (and any
// method it changes) before registering it.
#include <sqlite3.h>

namespace vfs_passthrough {

// The default VFS the shim wraps: its pAppData.
inline sqlite3_vfs* real(sqlite3_vfs* shim) { return static_cast<sqlite3_vfs*>(shim->pAppData); }

inline int access(sqlite3_vfs* v, const char* n, int fl, int* out) { return real(v)->xAccess(real(v), n, fl, out); }
inline int fullpath(sqlite3_vfs* v, const char* n, int sz, char* out) { return real(v)->xFullPathname(real(v), n, sz, out); }
inline void* dlopen(sqlite3_vfs* v, const char* n) { return real(v)->xDlOpen(real(v), n); }
inline void dlerror(sqlite3_vfs* v, int n, char* m) { real(v)->xDlError(real(v), n, m); }
inline void (*dlsym(sqlite3_vfs* v, void* h, const char* s))(void) { return real(v)->xDlSym(real(v), h, s); }
inline void dlclose(sqlite3_vfs* v, void* h) { real(v)->xDlClose(real(v), h); }
inline int randomness(sqlite3_vfs* v, int n, char* out) { return real(v)->xRandomness(real(v), n, out); }
inline int sleep(sqlite3_vfs* v, int us) { return real(v)->xSleep(real(v), us); }
inline int current_time(sqlite3_vfs* v, double* t) { return real(v)->xCurrentTime(real(v), t); }
inline int last_error(sqlite3_vfs* v, int n, char* m) { return real(v)->xGetLastError(real(v), n, m); }
inline int current_time64(sqlite3_vfs* v, sqlite3_int64* t) { return real(v)->xCurrentTimeInt64(real(v), t); }

// The file methods a shim hands on unchanged to the file it wraps, for a
// shim whose file struct gives the wrapped file through Real.
template <sqlite3_file* (*Real)(sqlite3_file*)>
struct FileMethods {
  static int size(sqlite3_file* f, sqlite3_int64* s) { return Real(f)->pMethods->xFileSize(Real(f), s); }
  static int lock(sqlite3_file* f, int l) { return Real(f)->pMethods->xLock(Real(f), l); }
  static int unlock(sqlite3_file* f, int l) { return Real(f)->pMethods->xUnlock(Real(f), l); }
  static int check(sqlite3_file* f, int* o) { return Real(f)->pMethods->xCheckReservedLock(Real(f), o); }
  static int fcntl(sqlite3_file* f, int op, void* a) { return Real(f)->pMethods->xFileControl(Real(f), op, a); }
  static int sector(sqlite3_file* f) { return Real(f)->pMethods->xSectorSize(Real(f)); }
  static int devchar(sqlite3_file* f) { return Real(f)->pMethods->xDeviceCharacteristics(Real(f)); }
  static int shmmap(sqlite3_file* f, int i, int sz, int ext, void volatile** pp) {
    return Real(f)->pMethods->xShmMap(Real(f), i, sz, ext, pp);
  }
  static int shmlock(sqlite3_file* f, int o, int n, int fl) { return Real(f)->pMethods->xShmLock(Real(f), o, n, fl); }
  static void shmbarrier(sqlite3_file* f) { Real(f)->pMethods->xShmBarrier(Real(f)); }
  static int shmunmap(sqlite3_file* f, int d) { return Real(f)->pMethods->xShmUnmap(Real(f), d); }
  static int fetch(sqlite3_file* f, sqlite3_int64 o, int n, void** pp) { return Real(f)->pMethods->xFetch(Real(f), o, n, pp); }
  static int unfetch(sqlite3_file* f, sqlite3_int64 o, void* p) { return Real(f)->pMethods->xUnfetch(Real(f), o, p); }

  // The shim's own close, read, write, truncate and sync (and file control,
  // where it answers some itself) with everything else handed on.
  static constexpr sqlite3_io_methods with(int (*close)(sqlite3_file*), int (*read)(sqlite3_file*, void*, int, sqlite3_int64),
                                           int (*write)(sqlite3_file*, const void*, int, sqlite3_int64),
                                           int (*truncate)(sqlite3_file*, sqlite3_int64), int (*sync)(sqlite3_file*, int),
                                           int (*file_control)(sqlite3_file*, int, void*) = fcntl) {
    return sqlite3_io_methods{3,     close,  read,     write,  truncate,   sync,     size,     lock,    unlock, check,
                              file_control, sector, devchar, shmmap, shmlock, shmbarrier, shmunmap, fetch, unfetch};
  }
};

// A shim named `name` over the default VFS whose files are `file_size`
// bytes of its own followed by the default VFS's file.
inline void fill(sqlite3_vfs& shim, const char* name, int file_size) {
  sqlite3_vfs* r = sqlite3_vfs_find(nullptr);
  shim.iVersion = 2;
  shim.szOsFile = file_size + r->szOsFile;
  shim.mxPathname = r->mxPathname;
  shim.zName = name;
  shim.pAppData = r;
  shim.xAccess = access;
  shim.xFullPathname = fullpath;
  shim.xDlOpen = dlopen;
  shim.xDlError = dlerror;
  shim.xDlSym = dlsym;
  shim.xDlClose = dlclose;
  shim.xRandomness = randomness;
  shim.xSleep = sleep;
  shim.xCurrentTime = current_time;
  shim.xGetLastError = last_error;
  shim.xCurrentTimeInt64 = current_time64;
}

}  // namespace vfs_passthrough
