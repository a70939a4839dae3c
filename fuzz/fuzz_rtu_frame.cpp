// libFuzzer target: the Modbus RTU request path from the bytes on the line.
// The input is a sequence of chunks [length][flags][bytes: unit, PDU, CRC lo,
// CRC hi]. Flag bit 0 asks the target to put the right CRC in the last two
// bytes first (so the fuzzer reaches the handler without solving CRC-16);
// otherwise the CRC is as given. Each chunk goes through the RTU framer
// (server/rtu_framer.hpp) byte by byte, followed by silence on the line, as
// server/rtu_server.cpp does: what the framer gives as a frame for the
// module's unit or broadcast (0) goes to ModbusService::handle with transport
// RTU; bad CRCs, overruns and other units' frames never reach it.
//
// Broadcast (unit 0) is applied but never answered: the frame is also played
// as a unicast to the module on a twin service, and both must end up with the
// same settings and the same motion after every frame, while the twin keeps
// the request invariants of fuzz_common.hpp (also run on a locked service).
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_common.hpp"
#include "server/rtu_framer.hpp"

namespace {

struct Services {
  using Harness = fuzz::Harness;
  Harness bus{Harness::Access::open, server::Transport::rtu};   // gets the frames as they come
  Harness twin{Harness::Access::open, server::Transport::rtu};  // broadcasts as unicasts
  Harness locked{Harness::Access::locked, server::Transport::rtu};
};

Services& services() {
  static Services s;
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) { return fuzz::initialize(services); }

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto& [bus, twin, locked] = services();
  bus.reset();
  twin.reset();
  locked.reset();
  std::size_t at = 0;
  std::vector<std::uint8_t> chunk;
  std::vector<std::vector<std::uint8_t>> frames;
  server::RtuFramer framer(fuzz::kModuleUnit);
  while (size - at >= 2) {
    const std::size_t length = data[at];
    const bool fix_crc = data[at + 1] & 1;
    at += 2;
    if (size - at < length) break;
    chunk.assign(data + at, data + at + length);
    at += length;
    if (fix_crc && chunk.size() >= 4) {
      const std::uint16_t crc = server::crc16(std::span<const std::uint8_t>(chunk).first(chunk.size() - 2));
      chunk[chunk.size() - 2] = static_cast<std::uint8_t>(crc & 0xFF);
      chunk[chunk.size() - 1] = static_cast<std::uint8_t>(crc >> 8);
    }
    frames.clear();
    for (std::uint8_t b : chunk)
      if (auto r = framer.push(b); r && r->event == server::RtuFramer::Event::frame) frames.push_back(std::move(r->frame));
    (void)framer.silence();
    for (const auto& frame : frames) {
      if (frame.size() < 4 || server::crc16(frame) != 0) fuzz::violated("the framer passed a frame whose CRC fails", 0, frame);
      const std::uint8_t unit = frame[0];
      if (unit != fuzz::kModuleUnit && unit != 0) continue;  // another unit on the bus
      const auto pdu = std::span<const std::uint8_t>(frame).subspan(1, frame.size() - 3);

      const server::Reply reply = unit == 0 ? bus.broadcast(pdu) : bus.request(unit, pdu);
      if (unit == 0 && reply.send) fuzz::violated("a broadcast was answered", unit, pdu);
      const server::Reply unicast = twin.request(fuzz::kModuleUnit, pdu);
      (void)locked.request(fuzz::kModuleUnit, pdu);
      if (unit == 0 && fuzz::accepted_write(pdu.empty() ? 0 : pdu[0], unicast) && fuzz::commands_motion(unit, pdu))
        bus.motion_allowed = true;
      if (bus.settings_now != twin.settings_now) fuzz::violated("a broadcast and a unicast changed different settings", unit, pdu);
      if (bus.moving() != twin.moving()) fuzz::violated("a broadcast and a unicast moved differently", unit, pdu);
      // The reply as it goes on the line: unit, PDU, CRC that checks.
      if (reply.send) {
        const auto out = server::rtu_frame(unit, reply.pdu);
        if (out.size() > 256 || server::crc16(out) != 0) fuzz::violated("reply RTU frame too long or bad CRC", unit, pdu);
      }
    }
  }
  bus.finish();
  twin.finish();
  locked.finish();
  return 0;
}
