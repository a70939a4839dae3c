#pragma once
// What a transport hands a request to: the unit id, the PDU and who sent it.
#include <fmt/format.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "pdu.hpp"

namespace server {

// Where a request came from: the rules differ (unit ids 0 and 0xFF, the
// --write-allow list, broadcasts, silence for unknown units). tls is
// Modbus/TCP Security: Modbus TCP inside TLS, the client known by its certificate.
// mqtt: commands of the Sparkplug B edge node (NCMD), with --mqtt-commands.
enum class Transport : std::uint8_t { tcp, rtu, tls, mqtt };
inline constexpr std::size_t kTransportCount = 4;  // arrays indexed by Transport

// "tcp", "rtu", "tls": for the log and the audit log's transport column.
constexpr std::string_view transport_name(Transport t) {
  switch (t) {
    case Transport::tcp: return "tcp";
    case Transport::rtu: return "rtu";
    case Transport::tls: return "tls";
    case Transport::mqtt: return "mqtt";
  }
  return "?";
}

// Modbus TCP framing and a network address: plain or inside TLS.
// Clients with an IP address of their own (--write-allow applies to them);
// an MQTT command comes through the broker, enabled by --mqtt-commands.
constexpr bool over_network(Transport t) { return t == Transport::tcp || t == Transport::tls; }

// What a client may change, each level including the ones before it. Plain
// TCP and RTU clients have `settings` (--write-allow and the unlock code still
// apply to them); a TLS client what its certificate's role grants
// (server/client_role.hpp).
enum class Access : std::uint8_t {
  read_only,  // reads only
  commands,   // also commands, the heartbeat, move targets, the homing permit
  settings,   // also settings, the settings lock and the simulator unit
};

struct ClientInfo {
  ClientInfo() = default;
  ClientInfo(std::uint64_t id, Transport transport, std::string address)
      : id(id), transport(transport), address(std::move(address)) {}

  std::uint64_t id = 0;                 // unique per connection (jog ownership)
  Transport transport = Transport::tcp;
  std::string address;                  // "127.0.0.1:40122" or "unit 5"
  Access access = Access::settings;
  std::string identity;                 // TLS: "CN=hmi-3,O=Plant (role operator)"; else empty
  bool broadcast = false;               // an RTU broadcast (unit 0): applied, never answered, never in an edit session
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
  // The same request answered only if that needs no waiting (an event loop
  // asks before it hands a write to a worker thread); nullopt: nothing was
  // done, call handle() where waiting is allowed.
  virtual std::optional<Reply> handle_now(std::uint8_t, std::span<const std::uint8_t>, const ClientInfo&) {
    return std::nullopt;
  }
  // The same request taken by the handler's own writer and answered later,
  // through done(reply) on the writer's thread, once decided (and committed
  // when it changes a setting): an event loop hands a write over without a
  // thread waiting for it. false: not taken, nothing was done; call handle()
  // where waiting is allowed. done is called exactly once for a taken request,
  // on the thread that decided it (the settings writer, the control loop), and
  // must not block; a reply handed over with Reply::resolve set is made by
  // calling resolve on the receiver's own thread before it is sent.
  virtual bool handle_later(std::uint8_t, std::span<const std::uint8_t>, const ClientInfo&,
                            std::function<void(Reply)>) {
    return false;
  }
  virtual void disconnected(const ClientInfo& client) = 0;
  // The jog buttons `client` holds are released (a serial master gone silent:
  // a line has no disconnect); its edit session stays. true: one was held.
  virtual bool release_jogs(const ClientInfo&) { return false; }
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
