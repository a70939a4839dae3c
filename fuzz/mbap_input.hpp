#pragma once
// The input of the MBAP fuzz targets (fuzz_tcp_request, fuzz_tls_roles): the
// byte stream a client sends on one connection, played through
// server::TcpConnection (the state machine the TCP and TLS servers' event
// loops run for each socket; server/tcp_connection.hpp) into a
// fuzz::Harness, whose invariants are checked on every request; every reply
// must go back as a valid MBAP frame for its request. Requests the loop
// would run off it (writes) run here in turn, as a worker would.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "fuzz_common.hpp"
#include "server/tcp_connection.hpp"

namespace fuzz {

// The transaction and unit of each whole frame of the input, in order: what
// the replies must carry.
inline std::vector<server::MbapHeader> frames_of(std::span<const std::uint8_t> bytes) {
  std::vector<server::MbapHeader> out;
  std::size_t at = 0;
  while (bytes.size() - at >= server::kMbapHeaderSize) {
    const auto h = server::parse_mbap(bytes.subspan(at).first<server::kMbapHeaderSize>());
    if (!h.valid() || bytes.size() - at - server::kMbapHeaderSize < h.pdu_size()) break;
    out.push_back(h);
    at += server::kMbapHeaderSize + h.pdu_size();
  }
  return out;
}

// The service behind the connection, with the invariants checked on every request.
class CheckedHandler final : public server::RequestHandler {
 public:
  explicit CheckedHandler(fuzz::Harness& harness) : harness_(harness) {}
  server::Reply handle(std::uint8_t unit, std::span<const std::uint8_t> pdu, const server::ClientInfo&) override {
    ++handled;
    return harness_.request(unit, pdu);
  }
  void disconnected(const server::ClientInfo&) override { harness_.finish(); }
  std::size_t handled = 0;

 private:
  fuzz::Harness& harness_;
};

// The input as a connection's bytes, arriving in pieces of up to 61 bytes
// (so frames split across reads); it ends where the input does. What goes
// back must be a valid MBAP frame again, for the request just handled.
class BufferChannel final : public server::ByteChannel {
 public:
  BufferChannel(std::span<const std::uint8_t> bytes, const CheckedHandler& handler)
      : bytes_(bytes), frames_(frames_of(bytes)), handler_(handler) {}
  int fd() const override { return -1; }
  server::ChannelIo read(std::span<std::uint8_t> out) override {
    if (at_ == bytes_.size()) return {server::ChannelIo::Status::want_read};  // the client sends no more
    const std::size_t n = std::min({out.size(), bytes_.size() - at_, std::size_t{61}});
    std::memcpy(out.data(), bytes_.data() + at_, n);
    at_ += n;
    return {server::ChannelIo::Status::done, n};
  }
  server::ChannelIo write(std::span<const std::uint8_t> frame) override {
    if (handler_.handled == 0 || handler_.handled > frames_.size())
      fuzz::violated("a reply with no request handled before it", 0, {});
    const server::MbapHeader request = frames_[handler_.handled - 1];
    if (frame.size() < server::kMbapHeaderSize) fuzz::violated("reply frame shorter than an MBAP header", request.unit, {});
    const auto back = server::parse_mbap(frame.first<server::kMbapHeaderSize>());
    const auto pdu = frame.subspan(server::kMbapHeaderSize);
    if (!back.valid() || back.pdu_size() != pdu.size() || back.transaction_id != request.transaction_id ||
        back.unit != request.unit)
      fuzz::violated("reply frame is not a valid MBAP frame for the request", request.unit, pdu);
    return {server::ChannelIo::Status::done, frame.size()};
  }

 private:
  std::span<const std::uint8_t> bytes_;
  std::vector<server::MbapHeader> frames_;
  const CheckedHandler& handler_;
  std::size_t at_ = 0;
};

class BufferHandshake final : public server::ChannelHandshake {
 public:
  explicit BufferHandshake(std::unique_ptr<server::ByteChannel> channel) : channel_(std::move(channel)) {}
  server::OpenStep step(server::ClientInfo&) override { return server::OpenStep::opened(); }
  std::unique_ptr<server::ByteChannel> channel() override { return std::move(channel_); }

 private:
  std::unique_ptr<server::ByteChannel> channel_;
};

// One connection's bytes into each harness, each from its reset state.
template <class Harnesses>
int play_connection(const std::uint8_t* data, std::size_t size, Harnesses& harnesses) {
  using Wait = server::TcpConnection::Wait;
  for (Harness& harness : harnesses) {
    harness.reset();
    CheckedHandler handler(harness);
    const auto now = std::chrono::steady_clock::now();
    server::TcpConnection connection(
        -1, harness.client,
        std::make_unique<BufferHandshake>(
            std::make_unique<BufferChannel>(std::span<const std::uint8_t>(data, size), handler)),
        0, 60'000, now);
    for (;;) {
      const Wait w = connection.advance(now, handler);
      if (w == Wait::again) continue;
      if (w != Wait::off_loop) break;  // closed, or waiting for bytes the input does not have
      connection.answered(handler.handle(connection.request().unit, connection.request().pdu, harness.client), now);
    }
    if (connection.opened()) handler.disconnected(harness.client);
  }
  return 0;
}

}  // namespace fuzz
