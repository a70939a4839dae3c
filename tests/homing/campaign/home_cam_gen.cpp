// home_cam axes (docs/limit-switches.md): a cam in mid-travel between two
// limit switches. Drawn from their own dice (stream 16) after everything
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
  Dice hc(m.seed, 16);  // 12: hard-stop axes by following error
  Dice hk(m.seed, 13);  // what goes wrong with them
  std::vector<std::size_t> cand = axes_where([&](std::size_t x) { return may_become_home_cam(x); });
  if (cand.empty() || !hc.chance(0.45)) return;
  const int n = hc.chance(0.25) ? 2 : 1;
  for (int i = 0; i < n && !cand.empty(); ++i) {
    const auto k = static_cast<std::size_t>(hc.integer(0, static_cast<int>(cand.size()) - 1));
    const std::size_t a = cand[k];
    home_cam_cause(a, home_cam_axis(a, hc), hk);
    cand.erase(cand.begin() + static_cast<std::ptrdiff_t>(k));
  }
}

// The axis keeps the motion settings draw_motion gave it (direction, speeds,
// acceleration, stop distance, debounce, sensor, pull-off, home position);
// everything that depends on where things are is drawn again here.
CamFrame Gen::home_cam_axis(std::size_t a, Dice& hc) {
  AxisSettings& s = m.settings.axes[a];
  sim::AxisConfig& c = m.sim.axes[a];
  AxisPlan& p = m.plan[a];
  CamFrame f;
  s.mode = HomingMode::home_cam;
  s.cam_edge = hc.chance(0.5) ? CamEdge::ahead : CamEdge::behind;
  const bool ahead = s.cam_edge == CamEdge::ahead;
  const double dir = dir_of(s);
  const double over = overshoot(s);
  // How far past its edge a release may come (hysteresis and noise).
  const double hyst = c.hysteresis_mm + 4 * c.noise_mm;
  f.top = hc.u(-50, 50);
  const double cam_len = over + hyst + hc.u(0.5, 30);
  f.bottom = f.top - cam_len;
  // The latch may cross the whole cam: its far edge may be the reference.
  s.max_backoff_mm = cam_len + over + hyst + 0.1 + hc.u(0.5, 5);
  // The reference: the edge on the cam_edge side, released leaving the cam
  // that way; the axis rests pull_off further on that side.
  const double ref_f = ahead ? f.bottom - c.hysteresis_mm : f.top + c.hysteresis_mm;
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
  switch (p.cam_start) {
    case CamStart::ahead: f.start = f.top + hyst + hc.u(0.5, 40); break;
    case CamStart::behind: f.start = f.bottom - hyst - hc.u(0.5, 40); break;
    case CamStart::on_cam:
    case CamStart::none: f.start = hc.u(f.bottom + hyst + 0.05, f.top - hyst - 0.05); break;
  }

  // Everything but the search stays between the switches: the cam and the
  // stop on it, the start, the rest point, the final position, jogs and
  // moves within the soft limits, lost steps and jogs before homing (3 mm).
  double lo = std::min({f.start, rest_f, f.bottom - hyst - over});
  double hi = std::max({f.start, rest_f, f.top + hyst + over});
  const auto reach = [&](double x) {
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  };
  // An axis in no sequence step is given its home position where it stands:
  // then they lie around its start (seed 12004845: a jog ran on past dead
  // limit switches into the stop).
  const auto from_start = [&](double machine_mm) { return f.start - dir * (machine_mm - s.home_position_mm); };
  if (s.final_move_enable) {
    reach(frame_of(s.final_position_mm));
    reach(from_start(s.final_position_mm));
  }
  if (s.soft_limits_enable) {
    for (const double limit : {s.soft_limit_min_mm, s.soft_limit_max_mm}) {
      reach(frame_of(limit));
      reach(from_start(limit));
    }
  }
  f.seek_side = lo - 3 - hc.u(0.5, 30);
  f.far_side = hi + 3 + hc.u(0.5, 30);

  s.limits_fitted = true;
  s.limits_nc = c.limits_nc = hc.chance(0.4);
  s.limit_overtravel_mm = limit_stop_distance_mm(s) * hc.u(1.05, 2.0) + hc.u(0.1, 5);
  // The search in each direction covers the whole travel between the switches.
  f.seek_margin = hc.u(1, 20);
  f.stop_beyond_seek = hc.u(0, 2);
  f.stop_beyond_far = hc.u(0, 2);
  place_home_cam(a, f);
  p.limits = true;
  return f;
}

void Gen::place_home_cam(std::size_t a, const CamFrame& f) {
  AxisSettings& s = m.settings.axes[a];
  sim::AxisConfig& c = m.sim.axes[a];
  const double dir = dir_of(s);
  s.max_seek_travel_mm = (f.far_side - f.seek_side) + s.limit_overtravel_mm + overshoot(s) + f.seek_margin;
  set_cam(a, dir, f.top, f.top - f.bottom, f.start);
  c.limit_min_mm = std::min(mirror(dir, f.seek_side), mirror(dir, f.far_side));
  c.limit_max_mm = std::max(mirror(dir, f.seek_side), mirror(dir, f.far_side));
  set_stops(a, dir, f.seek_side - s.limit_overtravel_mm - f.stop_beyond_seek,
            f.far_side + s.limit_overtravel_mm + f.stop_beyond_far);
  m.plan[a].start_gap_mm = f.start - f.top;
}

// What goes wrong with a home_cam axis (one thing at most, from its own
// dice): its cam beyond the limit switches (cam_not_found), its cam sensor
// dead (cam_not_found) or stuck active (not_released), its limit switches
// dead (docs/limit-switches.md: the search runs into the stop and ends in
// sensor_not_found) or stuck active (both_limits_active), or the limit
// switch on its reference side so close that the latch or the pull-off meets
// it (limit_in_homing). A fault from power-up only on an axis no event of the
// first cycle gives another (the simulator holds one fault at a time).
void Gen::home_cam_cause(std::size_t a, CamFrame f, Dice& hk) {
  AxisSettings& s = m.settings.axes[a];
  sim::AxisConfig& c = m.sim.axes[a];
  AxisPlan& p = m.plan[a];
  bool evented = false;
  for (const Event& e : m.events) evented = evented || e.axis == a;
  const auto start_fault = [&](sim::Fault fault) {
    p.start_fault = c.fault = fault;
  };
  const double u = hk.u(0, 1);
  if (u < 0.08) {
    // Beyond one of the mechanical stops: nowhere the search can reach.
    const double len = f.top - f.bottom;
    if (hk.chance(0.5)) {
      f.bottom = f.far_side + s.limit_overtravel_mm + f.stop_beyond_far + hk.u(1, 50);
      f.top = f.bottom + len;
    } else {
      f.top = f.seek_side - s.limit_overtravel_mm - f.stop_beyond_seek - hk.u(1, 50);
      f.bottom = f.top - len;
    }
    p.cam_missing = true;
  } else if (u < 0.16) {
    if (!evented) start_fault(s.sensor_nc ? sim::Fault::sensor_stuck_inactive
                                          : hk.pick({sim::Fault::sensor_stuck_inactive, sim::Fault::wire_break}));
  } else if (u < 0.20) {
    if (!evented) start_fault(s.sensor_nc ? hk.pick({sim::Fault::sensor_stuck_active, sim::Fault::wire_break})
                                          : sim::Fault::sensor_stuck_active);
  } else if (u < 0.28) {
    if (!evented) start_fault(sim::Fault::limits_dead);
  } else if (u < 0.33) {
    if (!evented) start_fault(sim::Fault::limits_stuck);
  } else if (u < 0.41) {
    // The switch on the reference side between the middle of the cam and
    // 0.05 mm short of the rest point; the start (and a jog before homing,
    // 3 mm toward the far side) on this side of it, the other switch moved
    // out where it must.
    const bool ahead = s.cam_edge == CamEdge::ahead;
    const double len = f.top - f.bottom;
    const double side = ahead ? -1.0 : 1.0;
    const double ref = ahead ? f.bottom : f.top;
    const double at = ref + side * hk.u(-0.5 * len, s.pull_off_mm + c.hysteresis_mm - 0.05);
    if (ahead) {
      if (f.start < at + 0.5) f.start = f.top + c.hysteresis_mm + 4 * c.noise_mm + hk.u(0.5, 3);
      f.seek_side = at;
      f.far_side = std::max(f.far_side, f.start + 3.5);
    } else {
      f.start = std::min(f.start, at - 3.5 - hk.u(0, 3));
      f.far_side = at;
      f.seek_side = std::min(f.seek_side, f.start - 3.5);
    }
    p.cam_start = f.start > f.top ? CamStart::ahead : f.start < f.bottom ? CamStart::behind : CamStart::on_cam;
    p.cam_at_limit = true;
  }
  place_home_cam(a, f);
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
