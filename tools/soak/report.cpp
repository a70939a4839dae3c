#include "report.hpp"

#include <fmt/format.h>
#include <sys/wait.h>

#include <algorithm>
#include <fstream>
#include <string>

namespace soak {

std::optional<long> vm_rss_kb(pid_t pid) {
  std::ifstream in(fmt::format("/proc/{}/status", pid));
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return std::nullopt;
}

namespace {

double percentile(std::vector<float>& v, double p) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::size_t>(std::clamp(p * static_cast<double>(v.size() - 1), 0.0, static_cast<double>(v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

}  // namespace

void print_summary(const RunFacts& run, Stats& total, const Shared& shared) {
  std::uint64_t errors = 0;
  for (const auto& [k, v] : total.errors) errors += v;
  fmt::print("homing_soak: {} clients for {:.1f} s (seed {})\n", run.clients, run.elapsed_s, run.seed);
  fmt::print("  {:<34} {}\n", "requests", total.requests);
  fmt::print("  {:<34} {:.0f}/s\n", "rate", total.requests / std::max(run.elapsed_s, 1e-9));
  fmt::print("  {:<34} {}\n", "errors", errors);
  for (const auto& [k, v] : total.errors) fmt::print("    {:<32} {}\n", k, v);
  fmt::print("  {:<34} {}\n", "exception 06 during homing (expected)", total.expected_busy);
  fmt::print("  {:<34} p50 {:.2f}  p90 {:.2f}  p99 {:.2f}  max {:.2f}\n", "latency ms", percentile(total.latency_ms, 0.5),
             percentile(total.latency_ms, 0.9), percentile(total.latency_ms, 0.99),
             total.latency_ms.empty() ? 0.0 : *std::max_element(total.latency_ms.begin(), total.latency_ms.end()));
  fmt::print("  {:<34} {}\n", "status polls", total.polls);
  fmt::print("  {:<34} {}\n", "settings writes read back", total.writes_verified);
  fmt::print("  {:<34} {}\n", "homing cycles completed", total.cycles_completed);
  fmt::print("  {:<34} {}\n", "homing cycles aborted", total.cycles_aborted);
  fmt::print("  {:<34} {}\n", "faults injected", total.faults_injected);
  auto rss = [](const std::optional<long>& v) { return v ? fmt::format("{} kB", *v) : std::string("unknown (--pid)"); };
  fmt::print("  {:<34} {} -> {}\n", "homingd VmRSS start -> end", rss(run.rss_start_kb), rss(run.rss_end_kb));
  if (run.exit_status)
    fmt::print("  {:<34} {}\n", "homingd exit after SIGTERM",
               WIFEXITED(*run.exit_status) ? WEXITSTATUS(*run.exit_status) : -1);
  fmt::print("  {:<34} {}\n", "invariant violations", shared.violation_count);
  for (const auto& v : shared.violations) fmt::print("    - {}\n", v);
}

}  // namespace soak
