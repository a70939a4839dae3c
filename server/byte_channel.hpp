#pragma once
// The bytes of one connection as its event loop moves them
// (server/tcp_connection.hpp): a plain socket, or a TLS session on one
// (server/tls_channel.hpp). No call waits; each says what it waits for, and
// the loop waits on fd() with its own deadlines.
#include <cstddef>
#include <cstdint>
#include <span>

namespace server {

struct ChannelIo {
  enum class Status : std::uint8_t { done, want_read, want_write, closed };
  Status status = Status::done;
  std::size_t bytes = 0;  // moved, when done
};

class ByteChannel {
 public:
  virtual ~ByteChannel() = default;
  virtual int fd() const = 0;
  virtual ChannelIo read(std::span<std::uint8_t> out) = 0;
  virtual ChannelIo write(std::span<const std::uint8_t> bytes) = 0;
  // Bytes received already that poll() on fd() would not show (TLS decrypts ahead).
  virtual bool buffered() const { return false; }
};

// A plain TCP socket, not owned.
class SocketChannel final : public ByteChannel {
 public:
  explicit SocketChannel(int fd) : fd_(fd) {}
  int fd() const override { return fd_; }
  ChannelIo read(std::span<std::uint8_t> out) override;
  ChannelIo write(std::span<const std::uint8_t> bytes) override;

 private:
  int fd_;
};

}  // namespace server
