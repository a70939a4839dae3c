#include "line_diagnostics.hpp"

#include "registers/errors.hpp"

namespace server {
namespace {

// Positions in LineDiagnostics::Atomic, in sub-function order from 0B.
enum Counter : std::size_t { bus_messages, comm_errors, exceptions, server_messages, no_response, naks, busy, overruns };

constexpr std::uint16_t kFirstCounterSubFunction = 0x0B;

}  // namespace

void LineDiagnostics::bus_event(Transport transport, BusEvent event) {
  auto& c = by_transport_[static_cast<std::size_t>(transport)].c;
  ++c[bus_messages];
  if (event == BusEvent::comm_error) ++c[comm_errors];
  if (event == BusEvent::overrun) ++c[overruns];
}

void LineDiagnostics::addressed(Transport transport) {
  ++by_transport_[static_cast<std::size_t>(transport)].c[server_messages];
}

void LineDiagnostics::answered(Transport transport, const Reply& reply) {
  auto& c = by_transport_[static_cast<std::size_t>(transport)].c;
  if (!reply.send) {
    ++c[no_response];
    return;
  }
  if (reply.pdu.size() == 2 && (reply.pdu[0] & 0x80)) {
    ++c[exceptions];
    if (reply.pdu[1] == static_cast<std::uint8_t>(registers::ExceptionCode::server_device_busy)) ++c[busy];
  }
}

LineCounters LineDiagnostics::counters(Transport transport) const {
  const auto& c = by_transport_[static_cast<std::size_t>(transport)].c;
  return LineCounters{c[bus_messages], c[comm_errors], c[exceptions], c[server_messages],
                      c[no_response],  c[naks],        c[busy],       c[overruns]};
}

Reply LineDiagnostics::answer(Transport transport, const DiagnosticsRequest& request) {
  constexpr auto fc = static_cast<std::uint8_t>(FunctionCode::diagnostics);
  auto& c = by_transport_[static_cast<std::size_t>(transport)].c;
  Reply reply{true, {fc}};
  put16(reply.pdu, request.sub_function);
  switch (request.sub_function) {
    case DiagnosticsRequest::return_query_data:
      for (std::uint16_t w : request.data) put16(reply.pdu, w);
      return reply;
    case DiagnosticsRequest::restart_communications:
    case DiagnosticsRequest::clear_counters:
      // The module has no listen-only mode and no event log: a restart of
      // communications clears the counters, as clear does.
      for (auto& counter : c) counter = 0;
      put16(reply.pdu, request.data.empty() ? 0 : request.data[0]);
      return reply;
    default:
      put16(reply.pdu, c[request.sub_function - kFirstCounterSubFunction]);
      return reply;
  }
}

}  // namespace server
