#pragma once
// One accepted Modbus/TCP connection (plain or TLS) as its event loop
// (server/event_loop.hpp) drives it: the handshake, the frames, the replies
// and the deadlines, as a state machine that never waits. The loop calls
// advance() when the socket is ready or a deadline has passed; advance()
// does what can be done now and says what it waits for next.
//
// Deadlines: the next frame must begin within the idle timeout; the whole
// frame, not each of its pieces, must arrive within kFrameTimeoutMs of its
// first byte; a reply must leave within kFrameTimeoutMs; a TLS handshake
// must end within the opener's timeout of the accept.
//
// Requests are served one at a time, in order. A request that may wait
// (a write: a durable commit, a simulator edit answered once visible) is
// answered at once if the handler can do so without waiting
// (RequestHandler::handle_now: a command or the heartbeat while no settings
// commit is under way), else handed back to the loop to run off it; the
// connection reads nothing more until its reply is in.
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "byte_channel.hpp"
#include "channel_opener.hpp"
#include "mbap_framer.hpp"
#include "request_handler.hpp"

namespace server {

inline constexpr int kFrameTimeoutMs = 1000;
inline constexpr int kDrainMs = 500;            // a refused TLS client's last bytes read and dropped
inline constexpr int kFramesPerTurn = 16;       // then the loop serves the others before more

using SteadyTime = std::chrono::steady_clock::time_point;

// Whether a request may wait for something outside the loop: the writes
// (FC 05, 06, 15, 16, 22, 23) wait for the settings' durable commit or the
// control loop; reads are answered from memory at once.
bool may_wait(std::uint8_t function);

class TcpConnection {
 public:
  TcpConnection(int fd, ClientInfo client, std::unique_ptr<ChannelHandshake> handshake, int handshake_timeout_ms,
                int idle_timeout_ms, SteadyTime now);
  TcpConnection(const TcpConnection&) = delete;
  TcpConnection& operator=(const TcpConnection&) = delete;

  enum class Wait : std::uint8_t {
    read,     // the socket readable (or the deadline)
    write,    // the socket writable (or the deadline)
    again,    // more to do at once: frames buffered beyond this turn's share
    off_loop, // a request to run off the loop: take_request(), then answered()
    closed,   // done: the loop closes the socket (end_reason() says why)
  };
  Wait advance(SteadyTime now, RequestHandler& handler);
  // When advance() must run even if the socket stays quiet (none while off the loop).
  std::optional<SteadyTime> deadline() const;

  struct Request {
    std::uint16_t transaction_id = 0;
    std::uint8_t unit = 0;
    std::vector<std::uint8_t> pdu;
  };
  // The request advance() handed off (Wait::off_loop).
  const Request& request() const { return off_loop_; }
  // Its reply, from the thread that ran it (through the loop).
  void answered(const Reply& reply, SteadyTime now);

  bool off_loop() const { return phase_ == Phase::off_loop; }
  int fd() const { return fd_; }
  const ClientInfo& client() const { return client_; }
  // Served requests (a handshake that never ended has none): disconnected() is owed.
  bool opened() const { return channel_ != nullptr; }
  const std::string& end_reason() const { return end_reason_; }
  // Refused before serving (the log line says "refused", not "disconnected").
  bool refused() const { return refused_; }
  // Sends what must go before the socket closes (TLS: close_notify); opened()
  // is false from then on.
  void say_goodbye() { channel_.reset(); }

 private:
  enum class Phase : std::uint8_t { opening, serving, off_loop, draining, closed };
  Wait open(SteadyTime now);
  Wait serve(SteadyTime now, RequestHandler& handler);
  Wait drain(SteadyTime now);
  Wait timed_out();
  Wait end(std::string reason);
  Wait refuse(std::string reason, bool drain, SteadyTime now);
  void queue_reply(std::uint16_t transaction_id, std::uint8_t unit, const Reply& reply, SteadyTime now);

  int fd_;
  ClientInfo client_;
  std::unique_ptr<ChannelHandshake> handshake_;
  std::unique_ptr<ByteChannel> channel_;
  Phase phase_ = Phase::opening;
  SteadyTime open_deadline_;
  int handshake_timeout_ms_;
  int idle_timeout_ms_;
  SteadyTime idle_deadline_{};
  SteadyTime frame_deadline_{};
  SteadyTime send_deadline_{};
  SteadyTime drain_deadline_{};
  MbapFramer framer_;
  std::vector<std::uint8_t> out_;
  std::size_t out_sent_ = 0;
  Request off_loop_;
  std::string end_reason_;
  bool refused_ = false;
};

}  // namespace server
