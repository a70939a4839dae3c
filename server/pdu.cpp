#include "pdu.hpp"

namespace server {

Reply exception_reply(std::uint8_t function, std::uint8_t code) {
  return Reply{true, {static_cast<std::uint8_t>(function | 0x80), code}};
}

std::uint16_t crc16(std::span<const std::uint8_t> bytes) {
  std::uint16_t crc = 0xFFFF;
  for (std::uint8_t b : bytes) {
    crc ^= b;
    for (int i = 0; i < 8; ++i) crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001) : static_cast<std::uint16_t>(crc >> 1);
  }
  return crc;
}

std::vector<std::uint8_t> tcp_frame(std::uint16_t tid, std::uint8_t unit, std::span<const std::uint8_t> pdu) {
  std::vector<std::uint8_t> out;
  out.reserve(7 + pdu.size());
  put16(out, tid);
  put16(out, 0);
  put16(out, static_cast<std::uint16_t>(pdu.size() + 1));
  out.push_back(unit);
  out.insert(out.end(), pdu.begin(), pdu.end());
  return out;
}

std::vector<std::uint8_t> rtu_frame(std::uint8_t unit, std::span<const std::uint8_t> pdu) {
  std::vector<std::uint8_t> out;
  out.reserve(3 + pdu.size());
  out.push_back(unit);
  out.insert(out.end(), pdu.begin(), pdu.end());
  const std::uint16_t crc = crc16(out);
  out.push_back(static_cast<std::uint8_t>(crc & 0xFF));  // CRC goes low byte first
  out.push_back(static_cast<std::uint8_t>(crc >> 8));
  return out;
}

}  // namespace server
