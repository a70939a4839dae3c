#pragma once
// Contact bounce: extra toggles after each true edge, at absolute times, that
// may spill into later periods. Always an even number per edge, so the contact
// settles on the level the true edge set.
#include <array>
#include <cstddef>
#include <cstdint>
#include <random>

namespace homing::sim {

class BounceQueue {
 public:
  void reseed(std::uint64_t seed, std::size_t axis);
  // Schedules the bounce of an edge at edge_time_s lasting up to bounce_s.
  void schedule(double edge_time_s, double bounce_s);
  // Pops the earliest toggle at or before until_s; false when none is due.
  bool pop_due(double until_s, double& time_s);
  std::size_t pending() const { return count_; }
  // Time of the earliest pending toggle (pending() > 0).
  double next_s() const { return times_s_[0]; }
  void clear() { count_ = 0; }

 private:
  std::array<double, 16> times_s_{};  // sorted ascending
  std::size_t count_ = 0;
  std::mt19937_64 rng_{};
};

}  // namespace homing::sim
