#include "tcp_connection.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>

#include <cerrno>

#include "pdu.hpp"

namespace server {
namespace {

using Status = ChannelIo::Status;
using std::chrono::milliseconds;

}  // namespace

bool may_wait(std::uint8_t function) {
  switch (function) {
    case 0x05: case 0x06: case 0x0F: case 0x10: case 0x16: case 0x17: return true;
    default: return false;
  }
}

TcpConnection::TcpConnection(int fd, ClientInfo client, std::unique_ptr<ChannelHandshake> handshake,
                             int handshake_timeout_ms, int idle_timeout_ms, SteadyTime now)
    : fd_(fd),
      client_(std::move(client)),
      handshake_(std::move(handshake)),
      // Plain TCP runs no handshake: it opens on the first turn.
      open_deadline_(now + milliseconds(handshake_timeout_ms > 0 ? handshake_timeout_ms : idle_timeout_ms)),
      handshake_timeout_ms_(handshake_timeout_ms),
      idle_timeout_ms_(idle_timeout_ms) {}

std::optional<SteadyTime> TcpConnection::deadline() const {
  switch (phase_) {
    case Phase::opening: return open_deadline_;
    case Phase::draining: return drain_deadline_;
    case Phase::off_loop:
    case Phase::closed: return std::nullopt;
    case Phase::serving:
      if (out_sent_ < out_.size()) return send_deadline_;
      if (framer_.front() == MbapFramer::Front::partial) return frame_deadline_;
      return idle_deadline_;
  }
  return std::nullopt;
}

TcpConnection::Wait TcpConnection::advance(SteadyTime now, RequestHandler& handler) {
  if (const auto d = deadline(); d && now >= *d) return timed_out();
  switch (phase_) {
    case Phase::opening: {
      const Wait w = open(now);
      return phase_ == Phase::serving ? serve(now, handler) : w;
    }
    case Phase::serving: return serve(now, handler);
    case Phase::draining: return drain(now);
    case Phase::off_loop: return Wait::off_loop;
    case Phase::closed: return Wait::closed;
  }
  return Wait::closed;
}

TcpConnection::Wait TcpConnection::timed_out() {
  switch (phase_) {
    case Phase::opening:
      refused_ = true;
      return end(fmt::format("TLS handshake not finished within {} ms of connecting", handshake_timeout_ms_));
    case Phase::draining: return end(end_reason_);
    case Phase::serving:
      if (out_sent_ < out_.size())
        return end(fmt::format("a reply not taken within {} ms (the client reads nothing)", kFrameTimeoutMs));
      if (framer_.front() == MbapFramer::Front::partial)
        return end(fmt::format("incomplete frame (not whole within {} ms of its first byte)", kFrameTimeoutMs));
      return end("idle timeout (--idle-timeout-s)");
    case Phase::off_loop:
    case Phase::closed: break;
  }
  return Wait::closed;
}

TcpConnection::Wait TcpConnection::end(std::string reason) {
  phase_ = Phase::closed;
  end_reason_ = std::move(reason);
  return Wait::closed;
}

TcpConnection::Wait TcpConnection::refuse(std::string reason, bool drain, SteadyTime now) {
  refused_ = true;
  if (!drain) return end(std::move(reason));
  ::shutdown(fd_, SHUT_WR);
  end_reason_ = std::move(reason);
  phase_ = Phase::draining;
  drain_deadline_ = now + milliseconds(kDrainMs);
  return Wait::read;
}

TcpConnection::Wait TcpConnection::open(SteadyTime now) {
  const OpenStep step = handshake_->step(client_);
  switch (step.kind) {
    case OpenStep::Kind::open:
      channel_ = handshake_->channel();
      handshake_.reset();
      phase_ = Phase::serving;
      idle_deadline_ = now + milliseconds(idle_timeout_ms_);
      return Wait::read;
    case OpenStep::Kind::want_read: return Wait::read;
    case OpenStep::Kind::want_write: return Wait::write;
    case OpenStep::Kind::refused: return refuse(step.reason, step.drain, now);
  }
  return Wait::closed;
}

TcpConnection::Wait TcpConnection::drain(SteadyTime) {
  std::uint8_t sink[512];
  for (;;) {
    const ssize_t r = ::recv(fd_, sink, sizeof sink, MSG_DONTWAIT);
    if (r > 0) continue;
    if (r < 0 && errno == EINTR) continue;
    if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return Wait::read;
    return end(end_reason_);
  }
}

void TcpConnection::queue_reply(std::uint16_t transaction_id, std::uint8_t unit, const Reply& reply, SteadyTime now) {
  if (reply.send) {
    const auto frame = tcp_frame(transaction_id, unit, reply.pdu);
    if (out_sent_ == out_.size()) {
      out_.clear();
      out_sent_ = 0;
    }
    out_.insert(out_.end(), frame.begin(), frame.end());
    send_deadline_ = now + milliseconds(kFrameTimeoutMs);
  }
  idle_deadline_ = now + milliseconds(idle_timeout_ms_);
  if (framer_.front() == MbapFramer::Front::partial) frame_deadline_ = now + milliseconds(kFrameTimeoutMs);
}

void TcpConnection::answered(const Reply& reply, SteadyTime now) {
  if (phase_ != Phase::off_loop) return;
  phase_ = Phase::serving;
  queue_reply(off_loop_.transaction_id, off_loop_.unit, reply, now);
}

TcpConnection::Wait TcpConnection::serve(SteadyTime now, RequestHandler& handler) {
  int frames = 0;
  bool replied = false;
  for (;;) {
    // The reply goes before the next request is read: one request at a time.
    while (out_sent_ < out_.size()) {
      const ChannelIo io = channel_->write(std::span(out_).subspan(out_sent_));
      if (io.status == Status::done) {
        out_sent_ += io.bytes;
        replied = true;
        continue;
      }
      if (io.status == Status::closed) return end("closed by the client");
      return io.status == Status::want_read ? Wait::read : Wait::write;
    }
    const FrameStep step = take_frame(framer_, handler, client_);
    switch (step.front) {
      case MbapFramer::Front::malformed: return end("malformed MBAP header");
      case MbapFramer::Front::frame: {
        if (frames == kFramesPerTurn) return Wait::again;
        ++frames;
        const std::uint8_t function = step.pdu.empty() ? 0 : step.pdu[0];
        std::optional<Reply> now_reply;
        if (may_wait(function)) now_reply = handler.handle_now(step.header.unit, step.pdu, client_);
        if (may_wait(function) && !now_reply) {
          off_loop_ = Request{step.header.transaction_id, step.header.unit, {step.pdu.begin(), step.pdu.end()}};
          framer_.pop();
          phase_ = Phase::off_loop;
          return Wait::off_loop;
        }
        const Reply reply = now_reply ? std::move(*now_reply) : handler.handle(step.header.unit, step.pdu, client_);
        const MbapHeader h = step.header;
        framer_.pop();
        queue_reply(h.transaction_id, h.unit, reply, now);
        continue;
      }
      case MbapFramer::Front::none:
      case MbapFramer::Front::partial: break;
    }
    // A client that sends its next request the moment it has its reply
    // would otherwise be served again and again in one turn while the others
    // wait: once this turn has answered, the loop serves the others first
    // (the socket stays readable, so the next turn comes).
    if (replied) return channel_->buffered() ? Wait::again : Wait::read;
    const bool begun = step.front == MbapFramer::Front::partial;
    const ChannelIo io = channel_->read(framer_.space());
    if (io.status == Status::done) {
      if (!begun) frame_deadline_ = now + milliseconds(kFrameTimeoutMs);
      framer_.received(io.bytes);
      continue;
    }
    if (io.status == Status::closed) {
      return end(begun ? "incomplete frame (the client closed)" : "closed by the client");
    }
    return io.status == Status::want_write ? Wait::write : Wait::read;
  }
}

}  // namespace server
