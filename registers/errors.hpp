#pragma once
// Modbus exception codes as values, with a sentence for the log and the HMI.
#include <cstdint>
#include <string>
#include <string_view>

namespace registers {

// Numbers are the Modbus exception codes on the wire.
enum class ExceptionCode : std::uint8_t {
  illegal_function = 0x01,
  illegal_data_address = 0x02,
  illegal_data_value = 0x03,
  server_device_failure = 0x04,
  server_device_busy = 0x06,
  gateway_target_failed = 0x0B,  // Modbus TCP: a unit id nothing answers to
};

constexpr std::string_view exception_name(ExceptionCode c) {
  switch (c) {
    case ExceptionCode::illegal_function: return "illegal function";
    case ExceptionCode::illegal_data_address: return "illegal data address";
    case ExceptionCode::illegal_data_value: return "illegal data value";
    case ExceptionCode::server_device_failure: return "server device failure";
    case ExceptionCode::server_device_busy: return "server device busy";
    case ExceptionCode::gateway_target_failed: return "gateway target device failed to respond";
  }
  return "?";
}

// A refused request: the code to answer with and what a technician should know.
struct Refusal {
  ExceptionCode code = ExceptionCode::server_device_failure;
  std::string message;
};

}  // namespace registers
