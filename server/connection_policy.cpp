#include "connection_policy.hpp"

#include <algorithm>
#include <optional>

namespace server {
namespace {

int count_of(std::span<const HeldConnection> held, std::uint32_t ip) {
  return static_cast<int>(std::count_if(held.begin(), held.end(), [ip](const HeldConnection& h) { return h.peer.ip == ip; }));
}

}  // namespace

Admission admit(std::span<const HeldConnection> held, const Peer& newcomer, const ConnectionLimits& limits) {
  Admission out;
  out.address_count = count_of(held, newcomer.ip);
  if (limits.max_per_address > 0 && out.address_count >= limits.max_per_address) {
    out.kind = Admission::Kind::refuse_address_cap;
    return out;
  }
  if (static_cast<int>(held.size()) < limits.max_clients) return out;
  std::optional<std::size_t> oldest;
  for (std::size_t i = 0; i < held.size(); ++i) {
    const HeldConnection& h = held[i];
    if (h.peer.privileged) continue;
    if (!newcomer.privileged && count_of(held, h.peer.ip) < out.address_count + 2) continue;
    if (!oldest || h.last_active_ns < held[*oldest].last_active_ns) oldest = i;
  }
  if (!oldest) {
    out.kind = Admission::Kind::refuse_full;
    return out;
  }
  out.kind = Admission::Kind::admit_closing;
  out.close = *oldest;
  return out;
}

}  // namespace server
