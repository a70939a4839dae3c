// libFuzzer target: the Modbus/TCP request path. The input is the byte stream
// a client sends on one connection. It is cut into frames exactly as
// server/tcp_server.cpp does (server/mbap.hpp: a bad MBAP header or an
// incomplete frame ends the connection), and every frame's unit id and PDU go
// to ModbusService::handle, the function the server calls. The same stream is
// played against three services: open, a client outside --write-allow, and
// settings locked by an unlock code. Besides "no crash" (ASan, UBSan) each
// request must keep the invariants of fuzz_common.hpp: nothing but an accepted
// settings write changes a setting, a read-only client gets no write accepted,
// locked settings change only with the code, nothing moves without an
// accepted coil write, and every reply fits a frame.
#include <array>
#include <cstddef>
#include <cstdint>

#include "fuzz_common.hpp"
#include "server/mbap.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet_logs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using fuzz::Harness;
  std::array<Harness, 3> services{Harness(Harness::Access::open), Harness(Harness::Access::read_only),
                                  Harness(Harness::Access::locked)};
  std::size_t at = 0;
  while (size - at >= server::kMbapHeaderSize) {
    const server::MbapHeader h =
        server::parse_mbap(std::span<const std::uint8_t, server::kMbapHeaderSize>(data + at, server::kMbapHeaderSize));
    if (!h.valid()) break;  // the server closes the connection
    at += server::kMbapHeaderSize;
    if (size - at < h.pdu_size()) break;  // incomplete frame: dropped at the frame timeout
    const std::span<const std::uint8_t> pdu(data + at, h.pdu_size());
    at += h.pdu_size();
    for (Harness& s : services) {
      const server::Reply reply = s.request(h.unit, pdu);
      // What goes back on the wire must be a valid MBAP frame again.
      if (reply.send) {
        const auto frame = server::tcp_frame(h.transaction_id, h.unit, reply.pdu);
        const auto back = server::parse_mbap(std::span<const std::uint8_t, server::kMbapHeaderSize>(
            frame.data(), server::kMbapHeaderSize));
        if (!back.valid() || back.pdu_size() + server::kMbapHeaderSize != frame.size() ||
            back.transaction_id != h.transaction_id)
          fuzz::violated("reply frame is not a valid MBAP frame", h.unit, pdu);
      }
    }
  }
  for (Harness& s : services) s.finish();
  return 0;
}
