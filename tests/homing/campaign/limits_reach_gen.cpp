// Limit switches within reach (docs/limit-switches.md "Hard limits"): on some
// axes with limit switches, one switch is pulled in from beyond everything the
// machine reaches to just beyond what its homing cycle reaches, with the soft
// limit on that side (and now and then the final position) past it, so that
// jogs, moves and final moves can run into it and the watch's "no carriage
// passes a limit switch by more than its stopping distance" can fail. From
// their own dice (stream 14), after everything else: other draws stay as
// they were.
#include <algorithm>
#include <cmath>

#include "gen.hpp"
#include "homing/motion.hpp"

namespace campaign {
namespace gen {

void Gen::limits_in_reach() {
  Dice lr(m.seed, 14);
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisPlan& p = m.plan[a];
    const HomingMode mode = m.settings.axes[a].mode;
    const bool eligible = p.limits && p.role == Role::plain && p.start_fault == sim::Fault::none && !p.cam_missing &&
                          !p.cam_at_limit && (mode_uses_switch(mode) && !mode_is_pushing(mode));
    if (eligible && lr.chance(0.35)) limit_in_reach(a, lr);
  }
}

// In carriage coordinates, along the side s (+1 or -1) of the switch pulled
// in: the homing cycle's own reach (the start and a jog before homing, the
// back-off or latch and the pull-off beyond the cam's edge on that side, a
// pre-move, an index pitch), the switch 0.5 to 10 mm beyond it, the stop its
// overtravel beyond the switch.
void Gen::limit_in_reach(std::size_t a, Dice& lr) {
  AxisSettings& s = m.settings.axes[a];
  sim::AxisConfig& c = m.sim.axes[a];
  AxisPlan& p = m.plan[a];
  const double dir = dir_of(s);
  const bool cam = s.mode == HomingMode::home_cam;
  // A plain switch axis: the end away from its sensor (the stop toward it is
  // what its seek may reach); a home cam: either end.
  const double side = cam ? lr.sign() : -dir;
  const auto along = [&](double x) { return side * x; };
  const double hyst = c.hysteresis_mm + 4 * c.noise_mm;
  const double edge = side > 0 ? c.sensor_max_mm : c.sensor_min_mm;  // the cam's edge on that side
  double reach = 0, rest = 0, unsure = 0.1;
  // The jog before homing: 3 mm beyond the start, then its braking at jog
  // feedrate and one late period (seed 192007033 of a release run: 781 mm/s
  // brakes over 5.8 mm, into a switch pulled in 4.2 mm from the start).
  const double jog_v = mm_per_min_to_mm_per_s(s.jog_feedrate_mm_per_min);
  const double jog = 3 + stop_distance_mm(jog_v, s.acceleration_mm_per_s2) + jog_v * m.max_dt_s;
  if (cam) {
    const double cam_side = s.cam_edge == CamEdge::ahead ? dir : -dir;
    const double ref = cam_side > 0 ? c.sensor_max_mm : c.sensor_min_mm;
    rest = ref + cam_side * (c.hysteresis_mm + s.pull_off_mm);
    reach = std::max({along(c.actual_position_mm) + jog, along(edge) + hyst + overshoot(s) + s.pull_off_mm + 3,
                      along(rest) + 3});
  } else {
    rest = p.cam_edge_mm - dir * ((mode_reapproaches(s.mode) ? 0.0 : c.hysteresis_mm) + s.pull_off_mm);
    if (s.mode == HomingMode::switch_index) unsure += s.index_pitch_mm;
    reach = std::max(along(c.actual_position_mm) + jog - 3, along(edge)) + s.max_backoff_mm + s.pull_off_mm +
            s.index_pitch_mm + s.pre_move_distance_mm + hyst + 3;
  }
  const double at = reach + lr.u(0.5, 10);
  const double now = side > 0 ? c.limit_max_mm : c.limit_min_mm;
  if (at >= along(now)) return;
  // The machine coordinate of a carriage place: home_position at the rest point.
  const auto machine = [&](double along_x) { return s.home_position_mm + side * (along_x - along(rest)); };
  double soft = machine(at + lr.u(1, 20) + unsure);
  if (s.final_move_enable && lr.chance(0.3)) {
    s.final_position_mm = machine(at + lr.u(1, 10) + unsure);
    soft = side > 0 ? std::max(soft, s.final_position_mm + 0.5) : std::min(soft, s.final_position_mm - 0.5);
  }
  if (side > 0) {
    s.soft_limit_max_mm = std::max(s.soft_limit_max_mm, soft);
    c.limit_max_mm = at;
    c.hard_stop_max_mm = at + s.limit_overtravel_mm + lr.u(0, 2);
  } else {
    s.soft_limit_min_mm = std::min(s.soft_limit_min_mm, soft);
    c.limit_min_mm = -at;
    c.hard_stop_min_mm = -at - s.limit_overtravel_mm - lr.u(0, 2);
  }
  p.reach_side = side > 0 ? 1 : -1;
}

}  // namespace gen
}  // namespace campaign
