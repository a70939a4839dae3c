#pragma once
// How good the reference of one homing cycle is: the figures measured from
// the edges the phases already see (README "Switch health", docs/health.md).
// Pure arithmetic; the phases feed it, publish() reports it.
#include <array>
#include <cstddef>
#include <span>

namespace homing {

// axis.<a>.latch_passes is bounded by this (the register's max).
inline constexpr int kMaxLatchPasses = 9;
// The approaches a setting asks for: 0 (settings made by hand) is one.
constexpr int latch_passes_of(int setting) {
  return setting < 1 ? 1 : setting > kMaxLatchPasses ? kMaxLatchPasses : setting;
}

// The trigger edges of this cycle's slow approaches, in the order found.
struct LatchEdges {
  std::array<double, kMaxLatchPasses> edge_mm{};
  int count = 0;
  void add(double x_mm) {
    if (count < kMaxLatchPasses) edge_mm[static_cast<std::size_t>(count++)] = x_mm;
  }
  std::span<const double> edges() const { return {edge_mm.data(), static_cast<std::size_t>(count)}; }
};

// The reference of several passes and how far they disagree.
struct EdgeStats {
  double median_mm = 0;  // the reference: one wild pass does not move it
  double spread_mm = 0;  // max - min
  double sigma_mm = 0;   // population standard deviation
};
EdgeStats edge_stats(std::span<const double> edges_mm);

// What one homing cycle measured of its axis's switch; 0 where this cycle's
// method does not cross the edge that figure needs.
struct SwitchHealth {
  int latch_passes = 0;         // slow approaches made this cycle
  double latch_spread_mm = 0;   // max - min of their edges
  double latch_sigma_mm = 0;    // their standard deviation
  double hysteresis_mm = 0;     // trigger edge vs the release edge next to it
  double seek_latch_mm = 0;     // seek edge minus latch edge, along the seek (input latency x speed)
  int chatter_edges = 0;        // raw transitions the debounce time swallowed this cycle
  double index_distance_mm = 0; // switch + index: release edge to the index pulse taken
  bool index_near_edge = false; // that distance is within kIndexMarginOfPitch of 0 or one pitch
  // Gantry slave (software-slaved or commutator): its reference edge minus
  // its master's, each taken from where its side stood when the cycle
  // started: the pair's squaring before the switch compensation. Set once
  // both edges are found (gantry_skew_measured).
  bool gantry_skew_measured = false;
  double gantry_skew_mm = 0;
};

// Switch + index: an index pulse this close (as a fraction of the pitch) to
// the switch edge, or to one pitch from it, may be missed or taken one pulse
// early when the switch edge moves by its noise: home one revolution off.
inline constexpr double kIndexMarginOfPitch = 0.1;
constexpr bool index_near_edge(double distance_mm, double pitch_mm) {
  return pitch_mm > 0 &&
         (distance_mm < kIndexMarginOfPitch * pitch_mm || distance_mm > (1 - kIndexMarginOfPitch) * pitch_mm);
}

// The edges one cycle crossed, as the phases find them.
struct CycleEdges {
  bool seek_seen = false;
  double seek_mm = 0;           // the trigger found by the seek
  bool release_seen = false;
  double release_mm = 0;        // the first release found by the back-off
  unsigned long transitions_at_start = 0;  // the input's counts when the cycle began
  unsigned long accepted_at_start = 0;
};

// The switch figures of a cycle whose reference was just found: dir is +1 or
// -1 toward the sensor; the transitions and accepted changes are the input's now.
void measure_switch(SwitchHealth& h, const CycleEdges& e, const LatchEdges& latch, double dir,
                    unsigned long transitions, unsigned long accepted);

}  // namespace homing
