#include "power_cut_vfs.hpp"

#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "vfs_passthrough.hpp"

namespace power_cut_vfs {
namespace {

constexpr std::int64_t kPiece = 512;  // what a torn write keeps or loses independently

enum class Kind { db, wal, journal };

std::string base_name(const std::string& path) { return path.substr(path.find_last_of('/') + 1); }

struct Op {
  bool truncate = false;
  std::int64_t offset = 0;  // truncate: the new size
  std::string data;
};

// A file's contents, apart from the name it has (a deleted WAL and the one
// created after it are two inodes under one name).
struct Inode {
  std::string durable;
  std::vector<Op> pending;  // since the last sync, in order
};

struct DirOp {
  std::string path;
  int inode = -1;  // -1: deleted
};

struct Model {
  std::mutex mu;
  std::vector<Inode> inodes;
  std::map<std::string, int> live;         // what the directory holds now
  std::map<std::string, int> durable_dir;  // as of the last directory sync
  std::vector<DirOp> dir_pending;          // since, in order
  std::map<std::string, Kind> kinds;       // every path modelled since the boot
  std::uint64_t countdown = 0;             // 0: not armed
  bool cut = false;
  CutPoint point{"-", "-"};
  int open = 0;
};
Model g;

sqlite3_vfs* g_real = nullptr;
sqlite3_vfs g_vfs{};

struct File {
  sqlite3_file base;
  sqlite3_file* real;
  int inode;     // -1: not modelled (temporary files)
  Kind kind;
  bool dirsync;  // the first sync also makes the directory durable
  const std::string* path;  // the key in g.kinds (stable: a map node)
};
File* F(sqlite3_file* f) { return reinterpret_cast<File*>(f); }
sqlite3_file* R(sqlite3_file* f) { return F(f)->real; }

// Requires g.mu. True when the operation must fail: the cut is now or was before.
bool stopped(const std::string& path, const char* op) {
  if (g.cut) return true;
  if (g.countdown > 0 && --g.countdown == 0) {
    g.cut = true;
    g.point = {base_name(path), op};
    return true;
  }
  return false;
}

void apply(std::string& image, const Op& op) {
  if (op.truncate) {
    image.resize(static_cast<std::size_t>(op.offset));
    return;
  }
  const auto end = static_cast<std::size_t>(op.offset) + op.data.size();
  if (image.size() < end) image.resize(end, '\0');
  std::memcpy(image.data() + op.offset, op.data.data(), op.data.size());
}

// A file already on the disk, read through its open handle (false: unreadable).
bool read_all(sqlite3_file* real, std::string& data) {
  sqlite3_int64 size = 0;
  if (real->pMethods->xFileSize(real, &size) != SQLITE_OK) return false;
  data.assign(static_cast<std::size_t>(size), '\0');
  return size == 0 || real->pMethods->xRead(real, data.data(), static_cast<int>(size), 0) == SQLITE_OK;
}

std::string read_path(const std::string& path) {
  std::string data;
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return data;
  char buf[65536];
  for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) > 0;) data.append(buf, static_cast<std::size_t>(n));
  ::close(fd);
  return data;
}

enum class Keep { none, all, some };

// What the disk holds of `ino` after the cut.
std::string survivor(const Inode& ino, Keep keep, std::mt19937_64& rng, Survivors& s) {
  std::string image = ino.durable;
  for (const auto& op : ino.pending) {
    if (op.truncate) {
      if (keep == Keep::all || (keep == Keep::some && rng() % 2 == 0)) apply(image, op);
      continue;
    }
    ++s.unsynced_writes;
    const std::int64_t end = op.offset + static_cast<std::int64_t>(op.data.size());
    for (std::int64_t a = op.offset; a < end;) {
      const std::int64_t b = std::min(end, (a / kPiece + 1) * kPiece);
      const auto roll = keep == Keep::none ? 2 : keep == Keep::all ? 0 : rng() % 5;  // 0-1 written, 2-3 lost, 4 torn
      if (roll == 2 || roll == 3) {
        ++s.pieces_lost;
      } else {
        if (image.size() < static_cast<std::size_t>(b)) image.resize(static_cast<std::size_t>(b), '\0');
        for (std::int64_t i = a; i < b; ++i)
          image[static_cast<std::size_t>(i)] =
              roll == 4 ? static_cast<char>(rng()) : op.data[static_cast<std::size_t>(i - op.offset)];
        if (roll == 4) ++s.pieces_torn;
      }
      a = b;
    }
  }
  return image;
}

void write_at(int fd, const std::string& image, std::int64_t from, std::int64_t to) {
  to = std::min<std::int64_t>(to, static_cast<std::int64_t>(image.size()));
  while (from < to) {
    ssize_t n = ::pwrite(fd, image.data() + from, static_cast<std::size_t>(to - from), from);
    if (n <= 0) throw std::runtime_error("power_cut_vfs: cannot write back a file");
    from += n;
  }
}

// Puts `image` on the disk at `path`. `on_disk`: the file there is `ino` with
// all its pending operations, so only what they touched differs.
void write_back(const std::string& path, const std::string& image, const Inode* on_disk) {
  int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("power_cut_vfs: cannot open " + path);
  const bool ranges = on_disk && std::none_of(on_disk->pending.begin(), on_disk->pending.end(),
                                              [](const Op& op) { return op.truncate; });
  if (ranges) {
    for (const auto& op : on_disk->pending)
      write_at(fd, image, op.offset, op.offset + static_cast<std::int64_t>(op.data.size()));
  } else {
    write_at(fd, image, 0, static_cast<std::int64_t>(image.size()));
  }
  int rc = ::ftruncate(fd, static_cast<off_t>(image.size()));
  ::close(fd);
  if (rc != 0) throw std::runtime_error("power_cut_vfs: cannot size " + path);
}

int x_close(sqlite3_file* f) {
  {
    std::lock_guard lock(g.mu);
    --g.open;
  }
  return R(f)->pMethods->xClose(R(f));
}
int x_read(sqlite3_file* f, void* b, int n, sqlite3_int64 o) { return R(f)->pMethods->xRead(R(f), b, n, o); }
int x_write(sqlite3_file* f, const void* b, int n, sqlite3_int64 o) {
  std::lock_guard lock(g.mu);
  File* file = F(f);
  if (file->inode < 0 ? g.cut : stopped(*file->path, "write")) return SQLITE_IOERR_WRITE;
  int rc = R(f)->pMethods->xWrite(R(f), b, n, o);
  if (rc == SQLITE_OK && file->inode >= 0)
    g.inodes[static_cast<std::size_t>(file->inode)].pending.push_back(
        {false, o, std::string(static_cast<const char*>(b), static_cast<std::size_t>(n))});
  return rc;
}
int x_truncate(sqlite3_file* f, sqlite3_int64 size) {
  std::lock_guard lock(g.mu);
  File* file = F(f);
  if (file->inode < 0 ? g.cut : stopped(*file->path, "truncate")) return SQLITE_IOERR_TRUNCATE;
  int rc = R(f)->pMethods->xTruncate(R(f), size);
  if (rc == SQLITE_OK && file->inode >= 0)
    g.inodes[static_cast<std::size_t>(file->inode)].pending.push_back({true, size, {}});
  return rc;
}
// Not passed on: the model is the durability.
int x_sync(sqlite3_file* f, int) {
  std::lock_guard lock(g.mu);
  File* file = F(f);
  if (file->inode < 0) return g.cut ? SQLITE_IOERR_FSYNC : SQLITE_OK;
  if (stopped(*file->path, "sync")) return SQLITE_IOERR_FSYNC;
  auto& ino = g.inodes[static_cast<std::size_t>(file->inode)];
  for (const auto& op : ino.pending) apply(ino.durable, op);
  ino.pending.clear();
  if (file->dirsync) {
    g.durable_dir = g.live;
    g.dir_pending.clear();
    file->dirsync = false;
  }
  return SQLITE_OK;
}

const sqlite3_io_methods kMethods = vfs_passthrough::FileMethods<R>::with(x_close, x_read, x_write, x_truncate, x_sync);

// Requires g.mu. The inode now under `path`, modelling a file that was on
// the disk before the shim saw it (and so is durable).
int adopt(const std::string& path, Kind kind, std::string contents) {
  const int id = static_cast<int>(g.inodes.size());
  g.inodes.push_back({std::move(contents), {}});
  g.live[path] = id;
  if (!g.kinds.contains(path)) {
    g.durable_dir[path] = id;
  } else {
    g.dir_pending.push_back({path, id});  // appeared again outside the shim
  }
  g.kinds.emplace(path, kind);
  return id;
}

int x_open(sqlite3_vfs*, sqlite3_filename name, sqlite3_file* f, int flags, int* out_flags) {
  std::lock_guard lock(g.mu);
  auto* file = reinterpret_cast<File*>(f);
  file->base.pMethods = nullptr;
  if (g.cut) return SQLITE_CANTOPEN;
  file->real = reinterpret_cast<sqlite3_file*>(file + 1);
  std::memset(file->real, 0, static_cast<std::size_t>(g_real->szOsFile));
  file->inode = -1;
  file->path = nullptr;
  file->kind = (flags & SQLITE_OPEN_WAL) ? Kind::wal : (flags & SQLITE_OPEN_MAIN_JOURNAL) ? Kind::journal : Kind::db;
  file->dirsync = (flags & SQLITE_OPEN_CREATE) && file->kind != Kind::db;
  const bool modelled = name && (flags & (SQLITE_OPEN_MAIN_DB | SQLITE_OPEN_WAL | SQLITE_OPEN_MAIN_JOURNAL));
  int existed = 0;
  if (modelled) g_real->xAccess(g_real, name, SQLITE_ACCESS_EXISTS, &existed);
  int rc = g_real->xOpen(g_real, name, file->real, flags, out_flags);
  if (!file->real->pMethods) return rc;
  file->base.pMethods = &kMethods;
  ++g.open;
  if (rc != SQLITE_OK || !modelled) return rc;
  const std::string path = name;
  if (auto it = g.live.find(path); it != g.live.end()) {
    file->inode = it->second;
  } else if (existed) {
    std::string contents;
    if (!read_all(file->real, contents)) return SQLITE_IOERR_READ;  // SQLite closes the file
    file->inode = adopt(path, file->kind, std::move(contents));
  } else {
    file->inode = static_cast<int>(g.inodes.size());
    g.inodes.push_back({});
    g.live[path] = file->inode;
    g.dir_pending.push_back({path, file->inode});
    g.kinds.emplace(path, file->kind);
  }
  file->path = &g.kinds.find(path)->first;
  return rc;
}

int x_delete(sqlite3_vfs*, const char* name, int dir_sync) {
  std::lock_guard lock(g.mu);
  const std::string path = name;
  const Kind kind = path.ends_with("-wal") ? Kind::wal : path.ends_with("-journal") ? Kind::journal : Kind::db;
  if (stopped(path, "delete")) return SQLITE_IOERR_DELETE;
  if (!g.live.contains(path)) {
    int exists = 0;
    g_real->xAccess(g_real, name, SQLITE_ACCESS_EXISTS, &exists);
    if (exists) adopt(path, kind, read_path(path));
  }
  int rc = g_real->xDelete(g_real, name, 0);  // the directory sync is modelled, not done
  if (rc == SQLITE_OK && g.live.erase(path) > 0) {
    g.dir_pending.push_back({path, -1});
    if (dir_sync) {
      g.durable_dir = g.live;
      g.dir_pending.clear();
    }
  }
  return rc;
}

}  // namespace

void install() {
  static std::once_flag once;
  std::call_once(once, [] {
    g_real = sqlite3_vfs_find(nullptr);
    vfs_passthrough::fill(g_vfs, kName, static_cast<int>(sizeof(File)));
    g_vfs.xOpen = x_open;
    g_vfs.xDelete = x_delete;
    sqlite3_vfs_register(&g_vfs, 0);
  });
}

void reset() {
  std::lock_guard lock(g.mu);
  if (g.open != 0) throw std::logic_error("power_cut_vfs::reset with files open");
  g.inodes.clear();
  g.live.clear();
  g.durable_dir.clear();
  g.dir_pending.clear();
  g.kinds.clear();
  g.countdown = 0;
  g.cut = false;
  g.point = {"-", "-"};
}

void arm(std::uint64_t n) {
  std::lock_guard lock(g.mu);
  g.countdown = std::max<std::uint64_t>(n, 1);
}

void cut_now() {
  std::lock_guard lock(g.mu);
  if (g.cut) return;
  g.cut = true;
  g.point = {"-", "-"};
}

bool cut_happened() {
  std::lock_guard lock(g.mu);
  return g.cut;
}

CutPoint cut_point() {
  std::lock_guard lock(g.mu);
  return g.point;
}

int open_files() {
  std::lock_guard lock(g.mu);
  return g.open;
}

Survivors apply_cut(std::mt19937_64& rng) {
  std::lock_guard lock(g.mu);
  if (g.open != 0) throw std::logic_error("power_cut_vfs::apply_cut with files open");
  if (!g.cut) throw std::logic_error("power_cut_vfs::apply_cut before the cut");
  Survivors s;
  auto dir = g.durable_dir;
  const std::size_t kept = rng() % (g.dir_pending.size() + 1);
  for (std::size_t i = 0; i < kept; ++i) {
    const auto& op = g.dir_pending[i];
    if (op.inode < 0)
      dir.erase(op.path);
    else
      dir[op.path] = op.inode;
  }
  s.directory_changes_undone = g.dir_pending.size() - kept;
  // Half the cuts lose every unsynced write (the classic model), a quarter
  // keep them all (the disk had written them back early, as after a kill),
  // a quarter keep, lose or tear each piece on its own.
  const auto mode = rng() % 4;
  const Keep keep = mode < 2 ? Keep::none : mode == 2 ? Keep::all : Keep::some;
  for (const auto& [path, kind] : g.kinds) {
    auto d = dir.find(path);
    if (d == dir.end()) {
      ::unlink(path.c_str());
      continue;
    }
    const Inode& ino = g.inodes[static_cast<std::size_t>(d->second)];
    auto live = g.live.find(path);
    // A file renamed away outside the shim (a backup put in place) is not there to patch.
    const bool same =
        live != g.live.end() && live->second == d->second && ::access(path.c_str(), F_OK) == 0;
    if (same && ino.pending.empty()) continue;  // the disk holds exactly the durable image
    write_back(path, survivor(ino, keep, rng, s), same ? &ino : nullptr);
  }
  for (const auto& [path, kind] : g.kinds)
    if (kind == Kind::db) ::unlink((path + "-shm").c_str());
  return s;
}

}  // namespace power_cut_vfs
