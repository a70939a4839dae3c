#pragma once
// One Modbus/TCP transaction framed here, on its own socket: for PDUs that
// libmodbus cannot frame or parse (FC 43/14).
#include <chrono>
#include <cstdint>
#include <vector>

namespace test_support {

// The reply PDU (function code first), or empty when nothing came within the timeout.
std::vector<std::uint8_t> raw_tcp_transaction(int port, std::uint8_t unit, const std::vector<std::uint8_t>& pdu,
                                              std::chrono::milliseconds timeout = std::chrono::milliseconds(2000));

}  // namespace test_support
