#pragma once
// The commissioning measurement (cmd.measure.<a>; docs/homing-methods.md
// "Commissioning measurement"): an axis homes, then travels at latch
// feedrate away from home to the opposite end of its travel (its limit
// switch, or a hard stop told by the stall input), and reports the usable
// travel and the settings that fit it. Nothing is written to the settings
// here: homingctl measure --apply writes them through the settings path.
#include <algorithm>
#include <cmath>

#include "modes.hpp"
#include "motion.hpp"
#include "settings.hpp"

namespace homing {

// The figures of the last measurement, in machine coordinates (mm).
struct Measurement {
  double usable_travel_mm = 0;     // from the home position toward the end, less the jog's stop distance
  double soft_limit_min_mm = 0;    // suggested: the home position and the usable end, the lower
  double soft_limit_max_mm = 0;    // suggested: the higher
  double max_seek_travel_mm = 0;   // suggested: the longest seek (from the far end to the sensor) plus a margin
};

// The share of the longest seek added to it for the suggested max_seek_travel,
// and the least margin (mm): a seek from the far end must fit, a dead sensor
// must not reach far past it.
inline constexpr double kSeekMarginShare = 0.1;
inline constexpr double kSeekMarginMin_mm = 5;

// How the opposite end of travel is told: its limit switch, or a hard stop by
// the drive's stall input; none refuses the measurement.
enum class TravelEnd : std::uint8_t { none, limit_switch, hard_stop };

// Methods whose home lies at one end of the travel (a switch they seek, a
// stop they push into); a home cam lies in mid-travel, and manual, absolute
// and drive methods home where they are told.
constexpr bool homes_at_travel_end(HomingMode mode) {
  const ModeRow& row = mode_row(mode);
  return (row.runs(Phase::seek) || row.runs(Phase::push_to_stop)) && !row.runs(Phase::cam_seek);
}

constexpr TravelEnd travel_end(const AxisSettings& s) {
  if (!homes_at_travel_end(s.mode)) return TravelEnd::none;
  if (s.limits_fitted) return TravelEnd::limit_switch;
  if (mode_row(s.mode).runs(Phase::push_to_stop) && s.stall_detect == StallDetect::stall_input)
    return TravelEnd::hard_stop;
  return TravelEnd::none;
}

// The figures from where the end was found. end_machine_mm: the end, in
// machine coordinates; toward: +1/-1, the direction travelled from home;
// longest_seek_mm: from the end to where the seek would find the sensor.
inline Measurement measurement_from(const AxisSettings& s, double end_machine_mm, double toward,
                                    double longest_seek_mm) {
  const double jog_stop_mm =
      s.acceleration_mm_per_s2 > 0
          ? stop_distance_mm(mm_per_min_to_mm_per_s(s.jog_feedrate_mm_per_min), s.acceleration_mm_per_s2)
          : 0;
  Measurement m;
  m.usable_travel_mm = std::max(0.0, (end_machine_mm - s.home_position_mm) * toward - jog_stop_mm);
  const double far_mm = s.home_position_mm + toward * m.usable_travel_mm;
  m.soft_limit_min_mm = std::min(s.home_position_mm, far_mm);
  m.soft_limit_max_mm = std::max(s.home_position_mm, far_mm);
  const double margin = std::max(kSeekMarginShare * longest_seek_mm, kSeekMarginMin_mm);
  m.max_seek_travel_mm = std::ceil(longest_seek_mm + margin);  // whole mm
  return m;
}

}  // namespace homing
