#pragma once
// What the soak run found: invariant violations (shared by every client) and
// request statistics (one per client, merged at the end).
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace soak {

struct Shared {
  std::mutex mu;
  std::vector<std::string> violations;
  std::uint64_t violation_count = 0;
  void violation(std::string what) {
    std::lock_guard lock(mu);
    ++violation_count;
    if (violations.size() < 40) violations.push_back(std::move(what));
  }
  std::mutex machine;  // the cycle and fault clients take turns
  std::string last_event;  // what the machine did last (under `machine`), for messages
  std::atomic<bool> stop{false};
};

struct Stats {
  std::uint64_t requests = 0;
  std::map<std::string, std::uint64_t> errors;  // by kind
  std::uint64_t expected_busy = 0;              // exception 06 on writes during homing
  std::vector<float> latency_ms;
  std::uint64_t writes_verified = 0, polls = 0;
  std::uint64_t cycles_completed = 0, cycles_aborted = 0, faults_injected = 0;
  void merge(const Stats& o) {
    requests += o.requests;
    for (const auto& [k, v] : o.errors) errors[k] += v;
    expected_busy += o.expected_busy;
    latency_ms.insert(latency_ms.end(), o.latency_ms.begin(), o.latency_ms.end());
    writes_verified += o.writes_verified;
    polls += o.polls;
    cycles_completed += o.cycles_completed;
    cycles_aborted += o.cycles_aborted;
    faults_injected += o.faults_injected;
  }
};

}  // namespace soak
