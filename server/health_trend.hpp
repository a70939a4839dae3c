#pragma once
// The health trend of one axis (docs/health.md "Trends"): after each cycle
// the runtime compares the figures the axis's last cycles left in the homing
// history. The decision is a pure function of those figures and the
// settings; the monitor reads the history, publishes the warning in
// axis.<a>.health_warning and logs it. A warning, never an alarm: the axis
// stays homed.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "homing/health.hpp"
#include "homing/settings.hpp"
#include "persistence/settings_store.hpp"

namespace server {

struct TrendSettings {
  std::size_t cycles = 0;         // global.trend_cycles: the window; 0 = no trend (index near edge still warns)
  double growth_fraction = 0;     // global.trend_growth_pct / 100
  double min_change_mm = 0;       // global.trend_min_change: a length figure grows at least this much
  double max_skew_change_mm = 0;  // the axis's max_skew_change: 0 = the skew is not checked
};
TrendSettings trend_settings(const homing::Settings& settings, std::size_t axis);

// Chatter is a count: it warns when it grew by the growth fraction and by at
// least this many edges per cycle (a few per cycle are normal for a
// mechanical contact with a debounce time).
inline constexpr double kChatterMinRise = 2;

// One warning with its figures: the figure now and what it was at the start
// of the cycles compared (for index_near_edge: the distance, and was = 0).
struct TrendVerdict {
  homing::HealthWarning warning = homing::HealthWarning::none;
  double now = 0;          // mm (the axis's unit), or edges per cycle for chatter
  double was = 0;
  std::size_t cycles = 0;  // how many cycles were compared
};

// The warnings the axis's history gives, most urgent first (index near edge,
// gantry skew changed, latch spread, hysteresis, seek-latch difference,
// chatter); empty when all is well. `history` is oldest first, its last entry
// the cycle just finished. Each figure is compared over the last
// `t.cycles` cycles, and only when every one of them measured it: what it
// was is the median of the window's first quarter; what it is now is the
// median of its last quarter (a wear figure must stay grown, one wild cycle
// does not warn) or, for the gantry skew, the last cycle (a coupling that
// slipped or a sensor that moved shows once: the next cycle squares the
// pair on its sensors again).
std::vector<TrendVerdict> judge_trend(std::span<const persistence::AxisHealth> history, const TrendSettings& t);

// The log's and homingctl's sentence: "X hysteresis 0.180 mm, was 0.050 mm
// over the last 20 cycles: the switch is wearing; check its mounting and plunger".
std::string verdict_text(const TrendVerdict& v, const homing::Settings& settings, std::size_t axis);

}  // namespace server
