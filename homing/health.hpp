#pragma once
// How good the reference of one homing cycle is: the figures measured from
// the edges the phases already see (docs/health.md).
// Pure arithmetic; the phases feed it, publish() reports it.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "enum_info.hpp"

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

// What the homing history says of an axis's health: the runtime's trend check
// (server/health_trend.hpp) compares the last cycles' figures and publishes
// one of these per axis (axis.<a>.health_warning). Not an alarm: the axis
// stays homed. Values are register values: append, never renumber.
enum class HealthWarning : std::uint8_t {
  none = 0,
  hysteresis_growing = 1,
  latch_spread_growing = 2,
  seek_latch_growing = 3,
  chatter = 4,
  index_near_edge = 5,
  gantry_skew_changed = 6,
};
inline constexpr EnumInfo<HealthWarning> kHealthWarningInfo[] = {
    {HealthWarning::none, "none", "no health warning"},
    {HealthWarning::hysteresis_growing, "hysteresis_growing",
     "the switch's hysteresis grew over the last cycles: the switch is wearing; check its mounting and plunger"},
    {HealthWarning::latch_spread_growing, "latch_spread_growing",
     "the latch passes' spread grew over the last cycles: check the switch's mounting, the cam and the latch feedrate"},
    {HealthWarning::seek_latch_growing, "seek_latch_growing",
     "the seek-latch difference grew over the last cycles: the input is slowing; check the input filter, the wiring "
     "and the switch's response"},
    {HealthWarning::chatter, "chatter",
     "the contact chatters more than it did: check the contact, its connector and noise on the line"},
    {HealthWarning::index_near_edge, "index_near_edge",
     "the index pulse lies near the switch edge: move the cam or the encoder's index by about half a pitch"},
    {HealthWarning::gantry_skew_changed, "gantry_skew_changed",
     "the gantry's squaring changed beyond max_skew_change: check the slave's coupling and sensor"},
};
static_assert(lists_every_value(kHealthWarningInfo, HealthWarning::gantry_skew_changed));
constexpr std::span<const EnumInfo<HealthWarning>> enum_table(HealthWarning) { return kHealthWarningInfo; }

// The edges one cycle crossed, as the phases find them.
struct CycleEdges {
  bool seek_seen = false;
  double seek_mm = 0;           // the trigger found by the seek
  bool release_seen = false;
  double release_mm = 0;        // the first release found by the back-off
  int releases = 0;             // release edges the back-offs met (one per latch pass)
  unsigned long transitions_at_start = 0;  // the input's counts when the cycle began
  unsigned long accepted_at_start = 0;
};

// The switch figures of a cycle whose reference was just found: dir is +1 or
// -1 toward the sensor; the transitions and accepted changes are the input's now.
void measure_switch(SwitchHealth& h, const CycleEdges& e, const LatchEdges& latch, double dir,
                    unsigned long transitions, unsigned long accepted);

}  // namespace homing
