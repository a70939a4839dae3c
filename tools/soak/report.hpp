#pragma once
// The soak run's summary on stdout, and the daemon's memory it includes.
#include <sys/types.h>

#include <optional>

#include "results.hpp"

namespace soak {

// VmRSS of a process in kB (from /proc), nullopt when it cannot be read.
std::optional<long> vm_rss_kb(pid_t pid);

struct RunFacts {
  int clients = 0;
  double elapsed_s = 0;
  std::uint64_t seed = 0;
  std::optional<long> rss_start_kb, rss_end_kb;
  std::optional<int> exit_status;  // of a spawned homingd after SIGTERM (waitpid status)
};

void print_summary(const RunFacts& run, Stats& total, const Shared& shared);

}  // namespace soak
