#pragma once
// Records every axis's velocity period by period and keeps the largest change
// relative to what its acceleration allows in that period (1 = exactly at the
// limit): a dead stop, or a ramp steeper than the drive can follow, shows as
// a ratio above 1.
#include <algorithm>
#include <array>
#include <cmath>

#include "homing/gantry.hpp"
#include "rig.hpp"

namespace rig {

struct AccelWatch {
  // The acceleration each axis may use: the one it moves with (a gantry
  // pair's lower one) unless a test sets it from the configuration itself.
  std::array<double, kAxisCount> accel{};
  std::array<double, kAxisCount> worst_ratio{};
  std::array<double, kAxisCount> worst_from{}, worst_to{};  // the velocities of the worst change
  std::array<double, kAxisCount> prev_v{};
  double engine_dt = 0;  // the period the engine integrates in its next step

  // Chains onto the rig's on_period, so other watches keep running.
  void start(Rig& r) {
    accel_from(motion_settings(r.settings));
    for (std::size_t a = 0; a < kAxisCount; ++a) prev_v[a] = r.axis(a).velocity_mm_per_s;
    worst_ratio = {};
    engine_dt = r.ran_dt_s;
    auto before = r.on_period;
    r.on_period = [this, before](Rig& rr) {
      if (before) before(rr);
      observe(rr);
    };
  }
  void accel_from(const Settings& s) {
    for (std::size_t a = 0; a < kAxisCount; ++a) accel[a] = s.axes[a].acceleration_mm_per_s2;
  }
  void observe(Rig& r) {
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      const double v = r.axis(a).velocity_mm_per_s;
      const double ratio = std::abs(v - prev_v[a]) / (accel[a] * engine_dt);
      if (ratio > worst_ratio[a]) {
        worst_ratio[a] = ratio;
        worst_from[a] = prev_v[a];
        worst_to[a] = v;
      }
      prev_v[a] = v;
    }
    engine_dt = r.ran_dt_s;
  }
  // Within the acceleration, but for rounding.
  bool within(std::size_t a) const { return worst_ratio[a] <= 1.0 + 1e-6; }
};

}  // namespace rig
