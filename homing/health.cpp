// Statistics of a cycle's latch edges.
#include "health.hpp"

#include <algorithm>
#include <cmath>

namespace homing {

EdgeStats edge_stats(std::span<const double> edges_mm) {
  EdgeStats st;
  if (edges_mm.empty()) return st;
  std::array<double, kMaxLatchPasses> sorted{};
  const std::size_t n = std::min(edges_mm.size(), sorted.size());
  std::copy_n(edges_mm.begin(), n, sorted.begin());
  std::sort(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(n));
  // An even count takes the mean of the middle two.
  st.median_mm = n % 2 ? sorted[n / 2] : (sorted[n / 2 - 1] + sorted[n / 2]) / 2;
  st.spread_mm = sorted[n - 1] - sorted[0];
  double mean = 0;
  for (std::size_t i = 0; i < n; ++i) mean += sorted[i];
  mean /= static_cast<double>(n);
  double var = 0;
  for (std::size_t i = 0; i < n; ++i) var += (sorted[i] - mean) * (sorted[i] - mean);
  st.sigma_mm = std::sqrt(var / static_cast<double>(n));
  return st;
}

void measure_switch(SwitchHealth& h, const CycleEdges& e, const LatchEdges& latch, double dir,
                    unsigned long transitions, unsigned long accepted) {
  const bool latched = latch.count > 0;
  // The trigger next to the release: the first slow approach, else the seek's.
  if (e.release_seen && (latched || e.seek_seen))
    h.hysteresis_mm = std::abs((latched ? latch.edge_mm[0] : e.seek_mm) - e.release_mm);
  if (e.seek_seen && latched) h.seek_latch_mm = (e.seek_mm - latch.edge_mm[0]) * dir;
  const long swallowed = static_cast<long>(transitions - e.transitions_at_start) -
                         static_cast<long>(accepted - e.accepted_at_start);
  h.chatter_edges = swallowed > 0 ? static_cast<int>(swallowed) : 0;
}

}  // namespace homing
