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

}  // namespace homing
