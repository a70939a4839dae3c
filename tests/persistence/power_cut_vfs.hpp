#pragma once
// A SQLite VFS shim ("powercut") over the default VFS that models what a
// power cut leaves on the disk, after SQLite's own crash tests (test6.c,
// crashsql). A SIGKILL keeps the page cache; a power cut keeps only what was
// synced, so the shim keeps, per file, the durable image (its bytes as of the
// last xSync) apart from the writes since.
//
// The model (conservative where the hardware is not):
//   - File contents: a write is durable once an xSync of that file returns.
//     At the cut, every later write is cut into 512-byte pieces and each piece
//     independently reached the disk, did not, or left garbage (a torn
//     sector); an unsynced truncate happened or not. Writes are limited to
//     the bytes they name (SQLite's unix VFS claims powersafe overwrite).
//   - Directory entries: a file created or deleted is durable only after a
//     directory sync: xDelete with its dirSync flag, or the first xSync of a
//     WAL or journal opened with SQLITE_OPEN_CREATE (the unix VFS then
//     fsyncs the directory, UNIXFILE_DIRSYNC). Of the later creations and
//     deletions a random prefix survives (a metadata journal keeps their
//     order). The fsync of the directory that persistence/durable_files.cpp
//     does itself is not seen, so it is not counted on.
//   - The -shm file is not data (SQLite rebuilds the WAL index from the WAL);
//     the cut removes it.
//   - Only files SQLite names as a main database, its journal or its WAL are
//     modelled (a backup's temporary file too); xSync is not passed on (the
//     model is the durability, so the test does not wait for a real disk).
//     What the store does beside SQLite (the backup's header write, fsync and
//     rename in store_backup.cpp) is not modelled: it happens as it happens.
// From the cut on, the machine is off: every write, truncate, sync, delete
// and open fails with an I/O error and changes nothing.
#include <cstdint>
#include <random>
#include <string>

namespace power_cut_vfs {

inline constexpr const char* kName = "powercut";

void install();  // idempotent

// Takes the files as they are on disk now as durable (a new boot) and
// forgets the cut. No file may be open through the shim.
void reset();
// The cut comes at the n-th write, truncate, sync or delete from now
// (n >= 1); that operation already fails.
void arm(std::uint64_t n);
void cut_now();      // the cut between two operations
bool cut_happened();

// Where the cut came: the file and the operation it stopped.
struct CutPoint {
  std::string file;  // the file's name without its directory, "-" between operations
  std::string op;    // "write", "truncate", "sync", "delete", "-"
};
CutPoint cut_point();

struct Survivors {
  std::size_t unsynced_writes = 0;  // writes since their file's last sync (pieces kept, lost or torn)
  std::size_t pieces_lost = 0;
  std::size_t pieces_torn = 0;
  std::size_t directory_changes_undone = 0;
};
// Puts on the disk what survives the cut (see the model above), drawing the
// choices from `rng`. Every file must be closed.
Survivors apply_cut(std::mt19937_64& rng);

int open_files();

}  // namespace power_cut_vfs
