#pragma once
// The campaign's only source of randomness: one generator per purpose, each
// seeded from the run's seed, so a seed repeats a run exactly. A new purpose
// takes a stream of its own, so that what the others draw stays as it was:
//   1 the machine (machine_gen.cpp, causes_gen.cpp)    2, 3 the run's acts, its periods
//   7 locking indexers                                  8 the run's indexer faults
//   11 limit switches on plain switch axes              12 hard-stop axes by following error
//   13 what goes wrong with home_cam axes               14 limit switches within reach
//   15 the run's acts at limit switches                 16 home_cam axes (home_cam_gen.cpp)
//   17 refcheck tolerances, far stops in reach          18 the run's measurements (service_acts.cpp)
//   19 the run's daemon restarts and reference checks  30 the failure policy
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <random>

namespace campaign {

class Dice {
 public:
  Dice(std::uint64_t seed, std::uint32_t stream) {
    std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32), stream};
    rng_.seed(seq);
  }
  double u(double lo, double hi) { return lo >= hi ? lo : std::uniform_real_distribution<double>(lo, hi)(rng_); }
  bool chance(double p) { return u(0, 1) < p; }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  double sign() { return chance(0.5) ? 1.0 : -1.0; }
  template <class T>
  T pick(std::initializer_list<T> items) {
    const auto i = std::uniform_int_distribution<std::size_t>(0, items.size() - 1)(rng_);
    return *(items.begin() + static_cast<std::ptrdiff_t>(i));
  }

 private:
  std::mt19937_64 rng_;
};

}  // namespace campaign
