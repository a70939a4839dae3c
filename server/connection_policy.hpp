#pragma once
// Who gets a connection when a client connects, as the Modbus Messaging on
// TCP/IP Implementation Guide describes connection management: a cap per
// client address, connections that privileged addresses (the PLC, the HMI)
// can always get, and, when the server is full, the least recently active
// connection that may give way is closed to make room. Pure: the TCP server
// passes what it holds and acts on the answer.
#include <cstddef>
#include <cstdint>
#include <span>

namespace server {

struct ConnectionLimits {
  int max_clients = 32;
  int max_per_address = 0;  // 0: as many as max_clients
};

// One connection held (or the one asking).
struct Peer {
  std::uint32_t ip = 0;  // IPv4, host byte order
  bool privileged = false;
};

struct HeldConnection {
  Peer peer;
  std::int64_t last_active_ns = 0;  // steady clock: the last request (or the accept)
};

struct Admission {
  enum class Kind {
    admit,              // room enough
    admit_closing,      // room made by closing held[close]
    refuse_address_cap, // the address already holds max_per_address
    refuse_full,        // full, and no connection may give way to this one
  };
  Kind kind = Kind::admit;
  std::size_t close = 0;
  int address_count = 0;  // connections the newcomer's address holds now
};

// A newcomer may displace a connection that is not privileged and is
//  - any such one if the newcomer is privileged (the PLC, the HMI get in);
//  - else one of an address holding at least two more connections than the
//    newcomer's address holds (so one address cannot hold every connection,
//    yet a full server of one connection per client does not churn, and an
//    address that fills the server is refused, not served by its own churn).
// Among those, the least recently active goes (the oldest accept on a tie).
Admission admit(std::span<const HeldConnection> held, const Peer& newcomer, const ConnectionLimits& limits);

}  // namespace server
