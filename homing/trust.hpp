#pragma once
// Position trust across restarts (docs/homing-methods.md "Position trust and
// the reference check"): how far an axis's coordinate can be believed, what
// the runtime keeps of an axis's last stop, and which homing methods offer a
// reference check instead of a full cycle. The runtime stores the last stops
// (persistence/) and hands them back at the next start; the engine only sees
// them as an input.
#include <array>
#include <cstdint>
#include <span>

#include "axes.hpp"
#include "enum_info.hpp"
#include "home_frame.hpp"
#include "modes.hpp"

namespace homing {

// axis.<a>.trust. Values are register values: never renumber.
enum class Trust : std::uint8_t {
  unknown = 0,              // nothing is known of where the axis is: a full cycle is needed
  last_stop_clean = 1,      // not homed, but it came to rest under control before this start: a reference check is offered
  reference_checked = 2,    // homed by a reference check against its stored position
  homed_this_power_on = 3,  // homed by a homing cycle since this start
};
inline constexpr EnumInfo<Trust> kTrustInfo[] = {
    {Trust::unknown, "unknown", "where the axis is is not known: home it with a full cycle"},
    {Trust::last_stop_clean, "last_stop_clean",
     "not homed; its last stop before this start was clean (homed, at rest, no alarm, shut down by SIGTERM or "
     "SIGINT): cmd.refcheck.<a> may confirm its stored position instead of a full cycle"},
    {Trust::reference_checked, "reference_checked",
     "homed by a reference check: its switch edge was found within refcheck_tolerance of where its stored "
     "position put it"},
    {Trust::homed_this_power_on, "homed_this_power_on", "homed by a homing cycle since this start"},
};
static_assert(lists_every_value(kTrustInfo, Trust::homed_this_power_on));
constexpr std::span<const EnumInfo<Trust>> enum_table(Trust) { return kTrustInfo; }

// What the runtime keeps of an axis when the module stops, and gives back at
// the next start.
struct LastStop {
  // It came to rest under control: homed, at rest, its drive enabled, no
  // alarm latched anywhere, at a clean shutdown. Only then is it offered a
  // reference check.
  bool clean = false;
  double position_mm = 0;  // machine coordinate it rested at
  HomeFrame frame{};       // the frame it was homed in (where its reference edge lay)
  friend bool operator==(const LastStop&, const LastStop&) = default;
};
using LastStops = std::array<LastStop, kAxisCount>;

// The reference check locates the edge a method homes on, at latch
// feedrate, from the side the axis rests on after homing: the trigger edge
// for a method that re-approaches its switch, the release edge (approach,
// then back off) for one that takes the release, a home cam's edge like a
// release. No check: methods without a switch edge (manual, absolute, hard
// stop, drive), and those whose reference is more than the switch edge
// (index: the pulse after it; pushing: the push aligns a hardware pair).
enum class RefcheckEdge : std::uint8_t { none, trigger, release };
constexpr RefcheckEdge refcheck_edge(const ModeRow& row) {
  if (row.coordinate != Coordinate::reference_edge || !row.needs_signal(Signal::home_sensor)) return RefcheckEdge::none;
  if (row.runs(Phase::index) || row.runs(Phase::push)) return RefcheckEdge::none;
  return row.runs(Phase::reapproach) ? RefcheckEdge::trigger : RefcheckEdge::release;
}
constexpr bool offers_refcheck(HomingMode mode) { return refcheck_edge(mode_row(mode)) != RefcheckEdge::none; }

}  // namespace homing
