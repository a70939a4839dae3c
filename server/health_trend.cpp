// The health trend's decision: pure arithmetic over the figures of an axis's
// last cycles (health_trend.hpp).
#include "health_trend.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "homing/axes.hpp"
#include "homing/gantry.hpp"

namespace server {

namespace {

using homing::HealthWarning;
using persistence::AxisHealth;

// A figure that wears: compared by how much it grew over the window.
struct GrowthFigure {
  HealthWarning warning;
  bool (*measured)(const AxisHealth&);  // the cycle crossed the edges the figure needs
  double (*value)(const AxisHealth&);
  bool counts;  // chatter: edges, held to kChatterMinRise instead of min_change_mm
};

// In the order they are reported when several grow.
constexpr GrowthFigure kGrowthFigures[] = {
    {HealthWarning::latch_spread_growing, [](const AxisHealth& h) { return h.latch_passes >= 2; },
     [](const AxisHealth& h) { return h.latch_spread_mm; }, false},
    {HealthWarning::hysteresis_growing, [](const AxisHealth& h) { return h.hysteresis_mm > 0; },
     [](const AxisHealth& h) { return h.hysteresis_mm; }, false},
    // Its sign says which edge came later; its size is the input's latency.
    {HealthWarning::seek_latch_growing, [](const AxisHealth& h) { return h.latch_passes >= 1 && h.seek_latch_mm != 0; },
     [](const AxisHealth& h) { return std::abs(h.seek_latch_mm); }, false},
    {HealthWarning::chatter, [](const AxisHealth&) { return true; },
     [](const AxisHealth& h) { return static_cast<double>(h.chatter_edges); }, true},
};

double median(std::vector<double> xs) {
  std::sort(xs.begin(), xs.end());
  const std::size_t n = xs.size();
  return n % 2 ? xs[n / 2] : (xs[n / 2 - 1] + xs[n / 2]) / 2;
}

// The window's values of a figure, oldest first, when every cycle of it measured the figure.
template <class Measured, class Value>
std::optional<std::vector<double>> series(std::span<const AxisHealth> window, Measured measured, Value value) {
  std::vector<double> xs;
  for (const AxisHealth& h : window) {
    if (!measured(h)) return std::nullopt;
    xs.push_back(value(h));
  }
  return xs;
}

// What it was: the median of the first quarter of the window (at least one cycle).
double was_of(const std::vector<double>& xs) {
  const std::size_t k = std::max<std::size_t>(1, xs.size() / 4);
  return median({xs.begin(), xs.begin() + static_cast<std::ptrdiff_t>(k)});
}
// What it is now, for a wear figure: the median of the last quarter.
double now_of(const std::vector<double>& xs) {
  const std::size_t k = std::max<std::size_t>(1, xs.size() / 4);
  return median({xs.end() - static_cast<std::ptrdiff_t>(k), xs.end()});
}

std::optional<TrendVerdict> growth(const GrowthFigure& f, std::span<const AxisHealth> window, const TrendSettings& t) {
  const auto xs = series(window, f.measured, f.value);
  if (!xs) return std::nullopt;
  const double was = was_of(*xs), now = now_of(*xs);
  const double least_rise = f.counts ? kChatterMinRise : t.min_change_mm;
  if (now > was * (1 + t.growth_fraction) && now - was >= least_rise)
    return TrendVerdict{f.warning, now, was, window.size()};
  return std::nullopt;
}

std::optional<TrendVerdict> skew_change(std::span<const AxisHealth> window, const TrendSettings& t) {
  if (t.max_skew_change_mm <= 0) return std::nullopt;
  const auto xs = series(
      window, [](const AxisHealth& h) { return h.gantry_skew_mm.has_value(); },
      [](const AxisHealth& h) { return *h.gantry_skew_mm; });
  if (!xs) return std::nullopt;
  const double was = was_of(*xs), now = xs->back();
  if (std::abs(now - was) > t.max_skew_change_mm)
    return TrendVerdict{HealthWarning::gantry_skew_changed, now, was, window.size()};
  return std::nullopt;
}

// A figure as the text shows it (3 decimals), never "-0.000".
double shown(double v) {
  const double r = std::round(v * 1000) / 1000;
  return r == 0 ? 0.0 : r;
}

}  // namespace

TrendSettings trend_settings(const homing::Settings& settings, std::size_t axis) {
  TrendSettings t;
  t.cycles = settings.global.trend_cycles;
  t.growth_fraction = settings.global.trend_growth_pct / 100.0;
  t.min_change_mm = settings.global.trend_min_change_mm;
  t.max_skew_change_mm = settings.axes[axis].max_skew_change_mm;
  return t;
}

std::vector<TrendVerdict> judge_trend(std::span<const AxisHealth> history, const TrendSettings& t) {
  std::vector<TrendVerdict> out;
  if (history.empty()) return out;
  // Its own cycle says it: the next cycle may home one index pitch off.
  if (history.back().index_near_edge)
    out.push_back({HealthWarning::index_near_edge, history.back().index_distance_mm, 0, 1});
  if (t.cycles == 0 || history.size() < t.cycles) return out;
  const auto window = history.last(t.cycles);
  if (auto v = skew_change(window, t)) out.push_back(*v);
  for (const GrowthFigure& f : kGrowthFigures)
    if (auto v = growth(f, window, t)) out.push_back(*v);
  return out;
}

std::string verdict_text(const TrendVerdict& v, const homing::Settings& settings, std::size_t axis) {
  const char x = homing::kAxisUpper[axis];
  const std::string_view u = homing::axis_unit(settings, axis);
  auto grown = [&](std::string_view figure, std::string_view advice) {
    return fmt::format("{} {} {:.3f} {}, was {:.3f} {} over the last {} cycles: {}", x, figure, shown(v.now), u,
                       shown(v.was), u, v.cycles, advice);
  };
  switch (v.warning) {
    case HealthWarning::none: return fmt::format("{}: no health warning", x);
    case HealthWarning::hysteresis_growing:
      return grown("hysteresis", "the switch is wearing; check its mounting and plunger");
    case HealthWarning::latch_spread_growing:
      return grown("latch spread", "the switch's edge repeats less well; check its mounting, the cam and the latch feedrate");
    case HealthWarning::seek_latch_growing:
      return grown("seek-latch difference",
                   "the input is slowing; check the input filter, the wiring and the switch's response");
    case HealthWarning::chatter:
      return fmt::format("{} chatter {:g} edges per cycle, was {:g} over the last {} cycles: the contact is wearing "
                         "out; check the contact, its connector and noise on the line",
                         x, v.now, v.was, v.cycles);
    case HealthWarning::index_near_edge:
      return fmt::format("{} index pulse {:.3f} {} from the switch edge (index_pitch {:g} {}): switch noise can home "
                         "one pitch off; move the cam or the encoder's index by about half a pitch",
                         x, shown(v.now), u, homing::motion_settings(settings).axes[axis].index_pitch_mm, u);
    case HealthWarning::gantry_skew_changed: {
      const int master = homing::gantry_master(settings, axis);
      const std::string pair = master >= 0 ? fmt::format("{}/{}", homing::kAxisUpper[static_cast<std::size_t>(master)], x)
                                           : std::string(1, x);
      return fmt::format("{} skew {:.3f} {}, was {:.3f} {} over the last {} cycles: check the slave's coupling and sensor",
                         pair, shown(v.now), u, shown(v.was), u, v.cycles);
    }
  }
  return fmt::format("{}: health warning {}", x, static_cast<int>(v.warning));
}

}  // namespace server
