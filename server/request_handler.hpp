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

class RequestHandler {
 public:
  virtual ~RequestHandler() = default;
  virtual Reply handle(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client) = 0;
  virtual void disconnected(const ClientInfo& client) = 0;
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
