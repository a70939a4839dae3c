#include "pdu.hpp"

namespace server {

Reply exception_reply(std::uint8_t function, std::uint8_t code) {
  return Reply{true, {static_cast<std::uint8_t>(function | 0x80), code}};
}

Reply registers_reply(std::uint8_t function, std::span<const std::uint16_t> words) {
  Reply reply{true, {function, static_cast<std::uint8_t>(words.size() * 2)}};
  reply.pdu.reserve(2 + words.size() * 2);
  for (std::uint16_t w : words) put16(reply.pdu, w);
  return reply;
}

Reply bits_reply(std::uint8_t function, std::span<const std::uint8_t> bits) {
  const std::size_t nbytes = (bits.size() + 7u) / 8u;
  Reply reply{true, {function, static_cast<std::uint8_t>(nbytes)}};
  reply.pdu.resize(2 + nbytes, 0);
  for (std::size_t i = 0; i < bits.size(); ++i)
    if (bits[i]) reply.pdu[2 + i / 8] |= static_cast<std::uint8_t>(1u << (i % 8));
  return reply;
}

Reply echo_reply(std::uint8_t function, std::uint16_t address, std::uint16_t value) {
  Reply reply{true, {function}};
  put16(reply.pdu, address);
  put16(reply.pdu, value);
  return reply;
}

Reply quantity_reply(std::uint8_t function, std::uint16_t start, std::uint16_t count) {
  return echo_reply(function, start, count);
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
