#pragma once
// Errors at the persistence edge are values. The message is written for a
// technician: it names the file and what failed, and where possible what to do.
#include <expected>
#include <string>
#include <string_view>

namespace persistence {

enum class ErrorKind {
  io,          // the disk failed (read, write, fsync)
  disk_full,   // no space left / size limit reached
  read_only,   // the database or its directory cannot be written
  corrupt,     // the file is not an intact database
  busy,        // another process holds the database locked
  invalid,     // the request or an imported file is not acceptable
  version,     // the database was written by a newer firmware
  internal,    // a bug: should never reach a user
};

std::string_view kind_name(ErrorKind kind);

struct Error {
  ErrorKind kind = ErrorKind::internal;
  std::string message;
};

template <class T>
using Result = std::expected<T, Error>;
using Status = std::expected<void, Error>;

inline std::unexpected<Error> fail(ErrorKind kind, std::string message) {
  return std::unexpected<Error>(Error{kind, std::move(message)});
}

}  // namespace persistence
