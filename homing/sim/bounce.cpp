#include "bounce.hpp"

#include <algorithm>

namespace homing::sim {

void BounceQueue::reseed(std::uint64_t seed, std::size_t axis) {
  // A stream of its own, so turning bounce on does not change the edge noise.
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(axis), 0xb0u};
  rng_.seed(seq);
}

void BounceQueue::schedule(double edge_time_s, double bounce_s) {
  if (bounce_s <= 0) return;
  const std::size_t toggles = (rng_() & 1u) ? 4 : 2;
  std::uniform_real_distribution<double> fraction(0.05, 1.0);
  std::array<double, 4> times{};
  for (std::size_t i = 0; i < toggles; ++i) times[i] = edge_time_s + bounce_s * fraction(rng_);
  // A full queue means a bounce storm already: dropping a whole even group keeps the parity.
  if (count_ + toggles > times_s_.size()) return;
  for (std::size_t i = 0; i < toggles; ++i) {
    const auto pos = std::upper_bound(times_s_.begin(), times_s_.begin() + count_, times[i]);
    std::move_backward(pos, times_s_.begin() + count_, times_s_.begin() + count_ + 1);
    *pos = times[i];
    ++count_;
  }
}

bool BounceQueue::pop_due(double until_s, double& time_s) {
  if (count_ == 0 || times_s_[0] > until_s) return false;
  time_s = times_s_[0];
  std::move(times_s_.begin() + 1, times_s_.begin() + count_, times_s_.begin());
  --count_;
  return true;
}

}  // namespace homing::sim
