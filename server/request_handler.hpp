#pragma once
// What a transport hands a request to: the unit id, the PDU and who sent it.
#include <cstdint>
#include <span>
#include <string>

#include "pdu.hpp"

namespace server {

struct ClientInfo {
  std::uint64_t id = 0;       // unique per connection (jog ownership)
  std::string transport;      // "tcp" or "rtu"
  std::string address;        // "127.0.0.1:40122" or "unit 5"
};

class RequestHandler {
 public:
  virtual ~RequestHandler() = default;
  virtual Reply handle(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client) = 0;
  virtual void disconnected(const ClientInfo& client) = 0;
};

}  // namespace server
