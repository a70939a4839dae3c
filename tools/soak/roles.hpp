#pragma once
// What each soak client does until Shared::stop: client 0 runs home/abort
// cycles, client 1 injects simulator faults (the two take turns on the
// machine), the others write settings they own and read them back, or poll
// status. Every broken invariant is a Shared::violation.
#include <cstdint>
#include <string>
#include <vector>

#include "counted_client.hpp"

namespace soak {

// A register one writer owns, so that its read-back is exact.
struct Owned {
  std::string name;
  std::int64_t lo, hi;
};

void cycle_role(CountedClient& c, Shared& shared, std::uint64_t seed);
void fault_role(CountedClient& c, Shared& shared, std::uint64_t seed);
void writer_role(CountedClient& c, Shared& shared, std::vector<Owned> regs, std::uint64_t seed);
void poller_role(CountedClient& c, Shared& shared, std::uint64_t seed);

}  // namespace soak
