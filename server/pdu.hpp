#pragma once
// Modbus PDUs (function code + data), independent of TCP or RTU framing. The
// server answers every request in this layer: libmodbus receives frames and
// checks them, but never sees a request before it has been validated here.
#include <cstdint>
#include <span>
#include <string>
#include <functional>
#include <vector>

namespace server {

inline constexpr std::size_t kMaxPdu = 253;

struct Reply {
  bool send = false;  // false: broadcast or a unit that stays silent
  std::vector<std::uint8_t> pdu;
  // Set on an answer handed over from a thread that must not log or wait (the
  // control loop answering a simulator write): the event loop that sends it
  // calls it first, on its own thread, for the answer to send.
  std::function<Reply()> resolve{};
};

Reply exception_reply(std::uint8_t function, std::uint8_t code);

// Normal replies: FC 3, 4, 23 (registers read), FC 1, 2 (bits read, one 0/1
// per byte of `bits`), FC 5, 6 (the request echoed), FC 15, 16 (start, quantity).
Reply registers_reply(std::uint8_t function, std::span<const std::uint16_t> words);
Reply bits_reply(std::uint8_t function, std::span<const std::uint8_t> bits);
Reply echo_reply(std::uint8_t function, std::uint16_t address, std::uint16_t value);
Reply quantity_reply(std::uint8_t function, std::uint16_t start, std::uint16_t count);

inline std::uint16_t be16(std::span<const std::uint8_t> b, std::size_t at) {
  return static_cast<std::uint16_t>((b[at] << 8) | b[at + 1]);
}
inline void put16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v >> 8));
  out.push_back(static_cast<std::uint8_t>(v & 0xFF));
}

// CRC-16/MODBUS of an RTU frame.
std::uint16_t crc16(std::span<const std::uint8_t> bytes);

// Frames a reply PDU for the wire.
std::vector<std::uint8_t> tcp_frame(std::uint16_t transaction_id, std::uint8_t unit, std::span<const std::uint8_t> pdu);
std::vector<std::uint8_t> rtu_frame(std::uint8_t unit, std::span<const std::uint8_t> pdu);

}  // namespace server
