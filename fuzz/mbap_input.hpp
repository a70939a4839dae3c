#pragma once
// The input of the MBAP fuzz targets (fuzz_tcp_request, fuzz_tls_roles): the
// byte stream a client sends on one connection, played through
// server::serve_mbap_stream (the framing loop the TCP and TLS servers run on
// their sockets) into a fuzz::Harness, whose invariants are checked on every
// request; every reply must go back as a valid MBAP frame for its request.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "fuzz_common.hpp"
#include "server/mbap_stream.hpp"

namespace fuzz {

// The input as a connection's bytes: it ends where the input does.
class BufferStream final : public server::MbapStream {
 public:
  explicit BufferStream(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  bool next_frame() override {
    frame_start_ = at_;
    return at_ < bytes_.size();
  }
  bool read(std::span<std::uint8_t> out) override {
    if (bytes_.size() - at_ < out.size()) return false;  // the client stops sending: the frame times out
    std::memcpy(out.data(), bytes_.data() + at_, out.size());
    at_ += out.size();
    return true;
  }
  // What goes back on the wire must be a valid MBAP frame again, for the same transaction.
  bool send(std::span<const std::uint8_t> frame) override {
    const auto request = parse_header(bytes_.subspan(frame_start_));
    if (frame.size() < server::kMbapHeaderSize) fuzz::violated("reply frame shorter than an MBAP header", request.unit, {});
    const auto back = parse_header(frame);
    const auto pdu = frame.subspan(server::kMbapHeaderSize);
    if (!back.valid() || back.pdu_size() != pdu.size() || back.transaction_id != request.transaction_id ||
        back.unit != request.unit)
      fuzz::violated("reply frame is not a valid MBAP frame for the request", request.unit, pdu);
    return true;
  }

 private:
  static server::MbapHeader parse_header(std::span<const std::uint8_t> bytes) {
    return server::parse_mbap(bytes.first<server::kMbapHeaderSize>());
  }
  std::span<const std::uint8_t> bytes_;
  std::size_t at_ = 0;
  std::size_t frame_start_ = 0;
};

// The service behind the framing loop, with the invariants checked on every request.
class CheckedHandler final : public server::RequestHandler {
 public:
  explicit CheckedHandler(fuzz::Harness& harness) : harness_(harness) {}
  server::Reply handle(std::uint8_t unit, std::span<const std::uint8_t> pdu, const server::ClientInfo&) override {
    return harness_.request(unit, pdu);
  }
  void disconnected(const server::ClientInfo&) override { harness_.finish(); }

 private:
  fuzz::Harness& harness_;
};

// One connection's bytes into each harness, each from its reset state.
template <class Harnesses>
int play_connection(const std::uint8_t* data, std::size_t size, Harnesses& harnesses) {
  for (Harness& harness : harnesses) {
    harness.reset();
    BufferStream stream(std::span<const std::uint8_t>(data, size));
    CheckedHandler handler(harness);
    (void)server::serve_mbap_stream(stream, handler, harness.client);
  }
  return 0;
}

}  // namespace fuzz
