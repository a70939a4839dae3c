#pragma once
// One TLS connection on a non-blocking socket it does not own. No call
// waits: each says whether it is done or what the socket must become ready
// for before it is called again (wait_for), so a caller can keep its own
// deadlines and stop flag.
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <expected>
#include <span>
#include <string>
#include <string_view>

#include "tls/handles.hpp"

namespace tls {

enum class Progress : std::uint8_t {
  done,        // the call did its work
  want_read,   // call again once the socket is readable
  want_write,  // call again once the socket is writable
  closed,      // the peer closed the connection
  failed,      // a TLS or socket error: error() says which
};

struct Io {
  Progress progress = Progress::done;
  std::size_t bytes = 0;  // read or written, when done
};

class Session {
 public:
  // The server side of an accepted connection.
  static std::expected<Session, std::string> accept(SSL_CTX* ctx, int fd);
  // The client side; the server's certificate must name `host` (an IP
  // address or a DNS name).
  static std::expected<Session, std::string> connect(SSL_CTX* ctx, int fd, const std::string& host);

  Progress handshake();
  Io read(std::span<std::uint8_t> out);
  Io write(std::span<const std::uint8_t> bytes);
  // Decrypted bytes waiting that poll() on the socket would not show.
  bool pending() const;
  // Sends close_notify once, without waiting for the peer's.
  void close();

  // Why the last call failed or what closed the connection.
  const std::string& error() const { return error_; }
  SSL* ssl() const { return ssl_.get(); }

 private:
  explicit Session(Ssl ssl) : ssl_(std::move(ssl)) {}
  Progress outcome(int rc);

  Ssl ssl_;
  std::string error_;
  bool closed_ = false;
};

// Waits until fd is ready for what `progress` asks (want_read: readable,
// want_write: writable); false when the deadline passes or *stop turns true.
bool wait_for(int fd, Progress progress, std::chrono::steady_clock::time_point deadline,
              const std::atomic<bool>* stop = nullptr);

}  // namespace tls
