#pragma once
// Records every axis's velocity period by period and keeps the largest change
// relative to what its acceleration allows in that period (1 = exactly at the
// limit): a dead stop, or a ramp steeper than the drive can follow, shows as
// a ratio above 1. A dead stop inside a long period can stay within a·dt from
// one period to the next, so the path each output ran in the period is read
// too: any jump of its velocity, and any piece steeper than the acceleration.
#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <string>

#include "homing/gantry.hpp"
#include "rig.hpp"

namespace rig {

struct AccelWatch {
  // The acceleration each axis may use: the one it moves with (a gantry
  // pair's lower one) unless a test sets it from the configuration itself.
  std::array<double, kAxisCount> accel{};
  std::array<double, kAxisCount> worst_ratio{};
  std::array<double, kAxisCount> worst_from{}, worst_to{};  // the velocities of the worst change
  std::array<double, kAxisCount> worst_jump{};  // mm/s, a velocity step inside a period's path
  std::array<double, kAxisCount> prev_v{};
  double engine_dt = 0;  // the period the engine integrates in its next step

  // Chains onto the rig's on_period, so other watches keep running.
  void start(Rig& r) {
    accel_from(motion_settings(r.settings));
    for (std::size_t a = 0; a < kAxisCount; ++a) prev_v[a] = r.axis(a).velocity_mm_per_s;
    worst_ratio = {};
    worst_jump = {};
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
      // The path the output just ran for this period (the simulator ran the same).
      const AxisOutputs& out = r.engine.outputs().axes[a];
      const MotionPath path = plan_path(out.motor, out.motion, r.ran_dt_s);
      for (std::size_t i = 0; i < path.count; ++i) {
        const MotionPiece& p = path.pieces[i];
        worst_ratio[a] = std::max(worst_ratio[a], std::abs(p.acceleration_mm_per_s2) / accel[a]);
        if (i + 1 < path.count) {
          const double v_end = p.velocity_mm_per_s + p.acceleration_mm_per_s2 * p.duration_s;
          worst_jump[a] = std::max(worst_jump[a], std::abs(path.pieces[i + 1].velocity_mm_per_s - v_end));
        }
      }
    }
    engine_dt = r.ran_dt_s;
  }
  // Within the acceleration, but for rounding.
  bool within(std::size_t a) const { return worst_ratio[a] <= 1.0 + 1e-6 && worst_jump[a] <= kJumpTolerance; }
  static constexpr double kJumpTolerance = 1e-6;  // mm/s: rounding only
  std::string describe(std::size_t a) const {
    std::ostringstream o;
    o << kAxisUpper[a] << ": worst change " << worst_from[a] << " -> " << worst_to[a] << " mm/s, "
      << worst_ratio[a] << " of the acceleration; worst jump inside a period " << worst_jump[a] << " mm/s";
    return o.str();
  }
};

}  // namespace rig
