#pragma once
// What a transport hands a request to: the unit id, the PDU and who sent it.
#include <fmt/format.h>

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "pdu.hpp"

namespace server {

// Where a request came from: the rules differ (unit ids 0 and 0xFF, the
// --write-allow list, broadcasts, silence for unknown units).
enum class Transport : std::uint8_t { tcp, rtu };

// "tcp", "rtu": for the log and the audit log's transport column.
constexpr std::string_view transport_name(Transport t) {
  switch (t) {
    case Transport::tcp: return "tcp";
    case Transport::rtu: return "rtu";
  }
  return "?";
}

struct ClientInfo {
  std::uint64_t id = 0;                 // unique per connection (jog ownership)
  Transport transport = Transport::tcp;
  std::string address;                  // "127.0.0.1:40122" or "unit 5"
};

// What a transport saw on its line, for the diagnostics counters (FC 08).
enum class BusEvent : std::uint8_t {
  message,     // a whole frame, for this module or another unit on the bus
  comm_error,  // a frame that failed its CRC (RTU) or a malformed MBAP header (TCP)
  overrun,     // a frame longer than the largest ADU
};

class RequestHandler {
 public:
  virtual ~RequestHandler() = default;
  virtual Reply handle(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client) = 0;
  virtual void disconnected(const ClientInfo& client) = 0;
  virtual void bus_event(Transport, BusEvent) {}
};

}  // namespace server

// Logs name the transport as transport_name() does.
template <>
struct fmt::formatter<server::Transport> : fmt::formatter<std::string_view> {
  template <typename FormatContext>
  auto format(server::Transport t, FormatContext& ctx) const {
    return fmt::formatter<std::string_view>::format(server::transport_name(t), ctx);
  }
};
