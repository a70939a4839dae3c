// libFuzzer target: the Modbus/TCP request path. The input is the byte stream
// a client sends on one connection. It goes through server::serve_mbap_stream,
// the framing loop server/tcp_server.cpp runs on a socket (a bad MBAP header
// or an incomplete frame ends the connection), which hands every frame's unit
// id and PDU to ModbusService::handle and tells it at the end that the client
// left. The same stream is played against three services: open, a client
// outside --write-allow, and settings locked by an unlock code. Besides "no
// crash" (ASan, UBSan) each request must keep the invariants of
// fuzz_common.hpp: nothing but an accepted settings write changes a setting,
// a read-only client gets no write accepted, locked settings change only with
// the code, nothing moves without an accepted coil write, and every reply fits
// a frame; and every reply goes back as a valid MBAP frame with the request's
// transaction id.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "fuzz_common.hpp"
#include "server/mbap_stream.hpp"

namespace {

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

std::array<fuzz::Harness, 3>& services() {
  using fuzz::Harness;
  static std::array<Harness, 3> s{Harness(Harness::Access::open), Harness(Harness::Access::read_only),
                                  Harness(Harness::Access::locked)};
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet_logs();
  (void)services();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  for (fuzz::Harness& service : services()) {
    service.reset();
    BufferStream stream(std::span<const std::uint8_t>(data, size));
    CheckedHandler handler(service);
    (void)server::serve_mbap_stream(stream, handler, service.client);
  }
  return 0;
}
