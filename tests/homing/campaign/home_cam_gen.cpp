// home_cam axes (docs/limit-switches.md): a cam in mid-travel between two
// limit switches. Drawn from their own dice (stream 12) after everything
// else, on plain axes nothing else is planned for, so every other draw of a
// seed stays as it was. Positions are drawn in the frame of machine_gen.cpp:
// the seek runs toward negative, the cam [bottom, top] lies somewhere
// between the switch the seek meets (low) and the other one (high).
#include <algorithm>
#include <cmath>

#include "gen.hpp"
#include "homing/motion.hpp"

namespace campaign {
namespace gen {

// A plain axis no slave_of names either way, not the axis made wrong on
// purpose, with nothing else planned for it (a start fault, a short cam, a
// shared limit resting on its sensor, an invalid encoder) and a mode that
// leaves no other state behind (a switch, pushing, manual or absolute axis).
bool Gen::may_become_home_cam(std::size_t a) const {
  const AxisSettings& s = m.settings.axes[a];
  const AxisPlan& p = m.plan[a];
  bool linked = s.slave_of != 0;
  for (const AxisSettings& o : m.settings.axes) linked = linked || o.slave_of == a + 1;
  const bool base = mode_uses_switch(s.mode) || s.mode == HomingMode::manual || mode_is_absolute(s.mode);
  return p.role == Role::plain && !linked && !s.shared_limit && base &&
         !(m.invalid != Invalid::none && m.invalid_axis == a) && p.start_fault == sim::Fault::none && !p.short_cam &&
         !p.rest_on_sensor && !p.encoder_invalid;
}

void Gen::home_cams() {
  Dice hc(m.seed, 12);
  std::vector<std::size_t> cand = axes_where([&](std::size_t x) { return may_become_home_cam(x); });
  if (cand.empty() || !hc.chance(0.45)) return;
  const int n = hc.chance(0.25) ? 2 : 1;
  for (int i = 0; i < n && !cand.empty(); ++i) {
    const auto k = static_cast<std::size_t>(hc.integer(0, static_cast<int>(cand.size()) - 1));
    home_cam_axis(cand[k], hc);
    cand.erase(cand.begin() + static_cast<std::ptrdiff_t>(k));
  }
}

// The axis keeps the motion settings draw_motion gave it (direction, speeds,
// acceleration, stop distance, debounce, sensor, pull-off, home position);
// everything that depends on where things are is drawn again here.
void Gen::home_cam_axis(std::size_t a, Dice& hc) {
  AxisSettings& s = m.settings.axes[a];
  sim::AxisConfig& c = m.sim.axes[a];
  AxisPlan& p = m.plan[a];
  s.mode = HomingMode::home_cam;
  s.cam_edge = hc.chance(0.5) ? CamEdge::ahead : CamEdge::behind;
  const bool ahead = s.cam_edge == CamEdge::ahead;
  const double dir = dir_of(s);
  const double over = overshoot(s);
  // How far past its edge a release may come (hysteresis and noise).
  const double hyst = c.hysteresis_mm + 4 * c.noise_mm;
  const double top_f = hc.u(-50, 50);
  const double cam_len = over + hyst + hc.u(0.5, 30);
  const double bottom_f = top_f - cam_len;
  // The latch may cross the whole cam: its far edge may be the reference.
  s.max_backoff_mm = cam_len + over + hyst + 0.1 + hc.u(0.5, 5);
  // The reference: the edge on the cam_edge side, released leaving the cam
  // that way; the axis rests pull_off further on that side.
  const double ref_f = ahead ? bottom_f - c.hysteresis_mm : top_f + c.hysteresis_mm;
  const double rest_f = ref_f + (ahead ? -1.0 : 1.0) * s.pull_off_mm;

  // Soft limits and the final position around the home position.
  s.soft_limits_enable = hc.chance(0.5);
  s.soft_limit_min_mm = s.home_position_mm - hc.u(0.5, 30);
  s.soft_limit_max_mm = s.home_position_mm + hc.u(0.5, 30);
  s.final_move_enable = hc.chance(0.3);
  s.final_position_mm = s.home_position_mm + hc.u(-20, 20);
  if (s.soft_limits_enable) s.final_position_mm = std::clamp(s.final_position_mm, s.soft_limit_min_mm, s.soft_limit_max_mm);
  // A machine coordinate's place in the frame (the carriage at rest_f reads home_position).
  const auto frame_of = [&](double machine_mm) { return rest_f - dir * (machine_mm - s.home_position_mm); };

  p.cam_start = hc.pick({CamStart::ahead, CamStart::behind, CamStart::on_cam});
  double start_f = 0;
  switch (p.cam_start) {
    case CamStart::ahead: start_f = top_f + hyst + hc.u(0.5, 40); break;
    case CamStart::behind: start_f = bottom_f - hyst - hc.u(0.5, 40); break;
    case CamStart::on_cam:
    case CamStart::none: start_f = hc.u(bottom_f + hyst + 0.05, top_f - hyst - 0.05); break;
  }

  // Everything but the search stays between the switches: the cam and the
  // stop on it, the start, the rest point, the final position, jogs and
  // moves within the soft limits, lost steps and jogs before homing (3 mm).
  double lo = std::min({start_f, rest_f, bottom_f - hyst - over});
  double hi = std::max({start_f, rest_f, top_f + hyst + over});
  const auto reach = [&](double f) {
    lo = std::min(lo, f);
    hi = std::max(hi, f);
  };
  if (s.final_move_enable) reach(frame_of(s.final_position_mm));
  if (s.soft_limits_enable) {
    reach(frame_of(s.soft_limit_min_mm));
    reach(frame_of(s.soft_limit_max_mm));
  }
  const double seek_side_f = lo - 3 - hc.u(0.5, 30);  // the switch the seek meets
  const double far_side_f = hi + 3 + hc.u(0.5, 30);

  s.limits_fitted = true;
  s.limits_nc = c.limits_nc = hc.chance(0.4);
  s.limit_overtravel_mm = limit_stop_distance_mm(s) * hc.u(1.05, 2.0) + hc.u(0.1, 5);
  // The search in each direction covers the whole travel between the switches.
  s.max_seek_travel_mm = (far_side_f - seek_side_f) + s.limit_overtravel_mm + over + hc.u(1, 20);
  set_cam(a, dir, top_f, cam_len, start_f);
  c.limit_min_mm = std::min(mirror(dir, seek_side_f), mirror(dir, far_side_f));
  c.limit_max_mm = std::max(mirror(dir, seek_side_f), mirror(dir, far_side_f));
  set_stops(a, dir, seek_side_f - s.limit_overtravel_mm - hc.u(0, 2), far_side_f + s.limit_overtravel_mm + hc.u(0, 2));
  p.start_gap_mm = start_f - top_f;
  p.limits = true;
}

}  // namespace gen

const char* cam_start_name(CamStart c) {
  switch (c) {
    case CamStart::none: return "none";
    case CamStart::ahead: return "the cam ahead (no reversal)";
    case CamStart::behind: return "the cam behind (reversal at the limit switch)";
    case CamStart::on_cam: return "on the cam";
  }
  return "?";
}

}  // namespace campaign
