#pragma once
// What a listener makes of an accepted connection before requests flow:
// plain TCP takes the socket as it is; TLS (server/tls_channel.hpp) runs the
// handshake and learns who the client is. A handshake never waits: each step
// says what the socket must become ready for, so an event loop runs many
// side by side and a stalled one delays nobody.
#include <memory>
#include <string>

#include "byte_channel.hpp"
#include "request_handler.hpp"

namespace server {

struct OpenStep {
  enum class Kind : std::uint8_t {
    open,        // channel() is ready to serve
    want_read,   // step again once the socket is readable
    want_write,  // step again once the socket is writable
    refused,     // reason says why (logged, then the connection is closed)
  };
  Kind kind = Kind::open;
  std::string reason;
  // Refused after the module sent an alert: the client must be able to read
  // it, so the module's side is shut first and what the client still sends
  // is read and dropped, briefly, before the socket closes (closing with
  // data unread would reset the connection and can lose the alert).
  bool drain = false;

  static OpenStep opened() { return {Kind::open, {}, false}; }
  static OpenStep wait_for(Kind kind) { return {kind, {}, false}; }
  static OpenStep refusal(std::string why, bool drain) { return {Kind::refused, std::move(why), drain}; }
};

class ChannelHandshake {
 public:
  virtual ~ChannelHandshake() = default;
  // May fill in client.access and client.identity.
  virtual OpenStep step(ClientInfo& client) = 0;
  // After step() said open.
  virtual std::unique_ptr<ByteChannel> channel() = 0;
};

class ChannelOpener {
 public:
  virtual ~ChannelOpener() = default;
  virtual Transport transport() const = 0;
  // The handshake of the connection on fd (a non-blocking socket, not owned).
  virtual std::unique_ptr<ChannelHandshake> begin(int fd) = 0;
  // How long a handshake may take from the accept (0: none is run).
  virtual int handshake_timeout_ms() const { return 0; }
};

}  // namespace server
