#pragma once
// What the simulated machine says really happened, to compare the engine with.
#include <catch2/catch.hpp>

#include "rig.hpp"

namespace rig {

// Edge-location tolerance of the issue: latch feedrate × control period / 10.
inline double edge_tolerance_mm(const AxisSettings& s, double period_s) {
  return mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min) * period_s / 10.0;
}

// Where the simulated switch really released / triggered last (carriage coordinates).
inline double last_release_mm(Rig& r, std::size_t a) {
  auto e = r.sim().last_edge(a, false);
  REQUIRE(e.has_value());
  return e->actual_mm;
}
inline double last_trigger_mm(Rig& r, std::size_t a) {
  auto e = r.sim().last_edge(a, true);
  REQUIRE(e.has_value());
  return e->actual_mm;
}

// The carriage position at which the machine coordinate equals the home
// position, for an axis homed on reference edge `edge_mm` (carriage coordinates).
inline double rest_point_mm(const AxisSettings& s, double edge_mm, double compensation_mm = 0) {
  const double dir = s.direction == Direction::positive ? 1.0 : -1.0;
  return edge_mm - dir * (s.pull_off_mm + compensation_mm);
}

// A homed axis's position must match the simulator's truth: machine position
// = home position + (carriage - rest point).
inline double true_position_mm(Rig& r, std::size_t a, double rest_mm) {
  return r.settings.axes[a].home_position_mm + (r.actual(a) - rest_mm);
}

}  // namespace rig
