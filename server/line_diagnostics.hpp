#pragma once
// Modbus serial line diagnostics (function 08) and their counters, one set per
// transport (RTU, TCP and TLS count apart). Transports report what they see on the
// line (bus_event); the service reports what it was asked and answered
// (addressed, answered); answer() serves the sub-functions the module implements.
#include <array>
#include <atomic>
#include <cstdint>

#include "pdu.hpp"
#include "request_decoder.hpp"
#include "request_handler.hpp"

namespace server {

// The counters of one transport, as sub-functions 0B..12 return them
// (each wraps at 65535, as a 16-bit answer must).
struct LineCounters {
  std::uint16_t bus_messages = 0;     // 0B: every frame seen on the line (any unit, good or bad)
  std::uint16_t comm_errors = 0;      // 0C: CRC errors (RTU), malformed MBAP headers (TCP)
  std::uint16_t exceptions = 0;       // 0D: exception responses this module returned
  std::uint16_t server_messages = 0;  // 0E: requests addressed to this module (or broadcast)
  std::uint16_t no_response = 0;      // 0F: of those, the ones not answered (broadcasts)
  std::uint16_t naks = 0;             // 10: NAK responses (exception 07): the module sends none
  std::uint16_t busy = 0;             // 11: exception 06 responses
  std::uint16_t overruns = 0;         // 12: frames longer than the largest ADU (RTU)
};

class LineDiagnostics {
 public:
  void bus_event(Transport transport, BusEvent event);
  // A request reached this module (before it is answered).
  void addressed(Transport transport);
  // What it was answered with (nothing, a reply, an exception).
  void answered(Transport transport, const Reply& reply);
  // Function 08: the reply, or the sub-function's effect (01, 0A clear the counters).
  Reply answer(Transport transport, const DiagnosticsRequest& request);

  LineCounters counters(Transport transport) const;

 private:
  struct Atomic {
    std::array<std::atomic<std::uint16_t>, 8> c{};
  };
  std::array<Atomic, kTransportCount> by_transport_{};  // index: Transport
};

}  // namespace server
