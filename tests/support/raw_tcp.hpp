#pragma once
// Modbus/TCP framed here, on a socket of its own: for PDUs that libmodbus
// cannot frame or parse (FC 43/14), and for requests sent back to back.
#include <chrono>
#include <cstdint>
#include <utility>
#include <vector>

namespace test_support {

// The reply PDU (function code first), or empty when nothing came within the
// timeout. The request goes with transaction id 0x1234 (so its first byte on
// the wire is 0x12).
std::vector<std::uint8_t> raw_tcp_transaction(int port, std::uint8_t unit, const std::vector<std::uint8_t>& pdu,
                                              std::chrono::milliseconds timeout = std::chrono::milliseconds(2000));

// Every request (unit, PDU) in one send, transaction ids first_tid,
// first_tid + 1, ...; the reply PDUs in the order they came, each paired with
// its transaction id. Stops at as many replies as requests, at the timeout,
// or when the server closes.
std::vector<std::pair<std::uint16_t, std::vector<std::uint8_t>>> raw_tcp_pipeline(
    int port, const std::vector<std::pair<std::uint8_t, std::vector<std::uint8_t>>>& requests,
    std::chrono::milliseconds timeout = std::chrono::milliseconds(2000), std::uint16_t first_tid = 1);

}  // namespace test_support
