#pragma once
// The MBAP header of a Modbus/TCP frame and the check the framing loop
// (server/mbap_framer.hpp) applies to it before reading the rest of the frame.
#include <cstddef>
#include <cstdint>
#include <span>

namespace server {

inline constexpr std::size_t kMbapHeaderSize = 7;  // transaction, protocol, length, unit
// The standard's largest MBAP length is 254 (a PDU of 253 bytes). A request
// whose one-byte byte count says more (a write of 124 registers or more, the
// largest FC 23's fixed part of 10 bytes and 255 data bytes) is still read
// whole and answered with exception 03, as a bad quantity: a client that asks
// too much learns why instead of losing its connection.
inline constexpr std::uint16_t kLongestMbapLength = 1 + 10 + 255;

struct MbapHeader {
  std::uint16_t transaction_id = 0;
  std::uint16_t protocol = 0;
  std::uint16_t length = 0;  // unit id + PDU
  std::uint8_t unit = 0;

  // MBAP length counts the unit id and the PDU; protocol 0 is Modbus.
  bool valid() const { return protocol == 0 && length >= 2 && length <= kLongestMbapLength; }
  // Bytes that follow the header (the PDU); meaningful only when valid().
  std::size_t pdu_size() const { return length - 1u; }
};

inline MbapHeader parse_mbap(std::span<const std::uint8_t, kMbapHeaderSize> h) {
  return MbapHeader{static_cast<std::uint16_t>((h[0] << 8) | h[1]), static_cast<std::uint16_t>((h[2] << 8) | h[3]),
                    static_cast<std::uint16_t>((h[4] << 8) | h[5]), h[6]};
}

}  // namespace server
