// Builds one random machine from a seed. Positions are drawn in a "frame"
// where the axis homes toward negative (the sensor's cam lies below its edge,
// the carriage starts above it), then mirrored for an axis homing positive.
#include <algorithm>
#include <cmath>

#include "gen.hpp"
#include "homing/motion.hpp"
#include "homing/settings_check.hpp"

namespace campaign {
namespace gen {

double Gen::overshoot(const AxisSettings& s) const {
  const double v = mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min);
  return s.max_stop_distance_mm + v * m.max_dt_s + 1e-3;
}

void Gen::draw_motion(AxisSettings& s, sim::AxisConfig& c, const PairDraw& pd) {
  s.direction = d.chance(0.5) ? Direction::negative : Direction::positive;
  // Mostly a router's speeds; one axis in ten up to the registers' maxima
  // (seek and jog 60,000 mm/min, acceleration 60,000 mm/s²).
  const bool fast = d.chance(0.1);
  double seek_v = fast ? d.u(40, 1000) : d.u(5, 40);
  double jog_v = fast ? d.u(20, 1000) : d.u(2, 20);
  s.acceleration_mm_per_s2 = fast ? d.u(2000, 60000) : d.u(100, 2000);
  const double a_pair = std::min(s.acceleration_mm_per_s2, pd.accel);
  if (pd.pair) {
    // A gantry stops from seek and jog feedrate within its misalignment.
    const double v_cap = std::sqrt(2 * a_pair * pd.misalignment * 0.7);
    seek_v = std::min(seek_v, v_cap);
    jog_v = std::min(jog_v, v_cap);
  }
  const double latch_v = d.u(std::min(0.5, seek_v / 3), std::min(5.0, seek_v / 2));
  s.seek_feedrate_mm_per_min = per_min(seek_v);
  s.latch_feedrate_mm_per_min = per_min(latch_v);
  s.jog_feedrate_mm_per_min = per_min(jog_v);
  s.debounce_ms = d.chance(0.5) ? 0 : d.u(0, 4);
  c.bounce_ms = s.debounce_ms > 1 && d.chance(0.5) ? d.u(0, s.debounce_ms * 0.9) : 0;
  const double debounce = std::max(s.debounce_ms, pd.debounce_ms);
  const double bounce = std::max(c.bounce_ms, pd.bounce_ms);
  const double needed = stop_distance_mm(seek_v, a_pair) + seek_v * debounce / 1000;
  s.max_stop_distance_mm = (needed + seek_v * bounce / 1000) * d.u(1.0, 3.0) + d.u(0, 0.1);
  c.hysteresis_mm = d.u(0, 0.2);
  c.noise_mm = d.chance(0.5) ? 0 : d.u(0, 0.01);
  s.sensor_nc = c.sensor_nc = d.chance(0.3);
  const double hyst = std::max(c.hysteresis_mm, pd.hysteresis);
  s.max_backoff_mm = overshoot(s) + hyst + 0.1 + d.u(0.5, 5);
  s.pull_off_mm = d.chance(0.2) ? 0 : d.u(0.1, 3);
  s.home_position_mm = d.u(-10, 10);
  s.pre_move_mode = d.pick({PreMove::none, PreMove::if_sensor_active, PreMove::always});
  s.pre_move_distance_mm = d.u(0.5, 5);
  s.push_distance_mm = d.u(0.3, 3);
  s.index_pitch_mm = d.u(1, 5);
  if (mode_is_pushing(s.mode)) s.max_backoff_mm += s.push_distance_mm;
}

double Gen::reference_f(const AxisSettings& e, const sim::AxisConfig& c, double edge_f, double index_r) {
  if (mode_reapproaches(e.mode)) return edge_f;
  const double release = edge_f + c.hysteresis_mm;
  return e.mode == HomingMode::switch_index ? release + index_r : release;
}

void Gen::place_index(sim::AxisConfig& c, double dir, double pitch, double release_f, double index_r) {
  c.index_pitch_mm = pitch;
  c.index_offset_mm = mirror(dir, release_f + index_r);
}

void Gen::set_cam(std::size_t a, double dir, double edge_f, double cam_len, double start_f) {
  sim::AxisConfig& c = m.sim.axes[a];
  const double p = mirror(dir, edge_f), q = mirror(dir, edge_f - cam_len);
  c.sensor_min_mm = std::min(p, q);
  c.sensor_max_mm = std::max(p, q);
  c.actual_position_mm = mirror(dir, start_f);
  m.plan[a].cam_edge_mm = p;
}

void Gen::set_stops(std::size_t a, double dir, double in_f, double out_f) {
  sim::AxisConfig& c = m.sim.axes[a];
  c.hard_stop_min_mm = std::min(mirror(dir, in_f), mirror(dir, out_f));
  c.hard_stop_max_mm = std::max(mirror(dir, in_f), mirror(dir, out_f));
}

double Gen::limits(AxisSettings& s, double hyst, bool shared, double room_max, double& far_away) {
  const double dir = dir_of(s);
  const bool pushing = mode_is_pushing(s.mode);
  double sensor_room = pushing ? d.u(0, s.pull_off_mm + hyst) : d.u(0.5, 30);
  if (shared) sensor_room = d.chance(0.7) ? s.pull_off_mm + hyst + d.u(1, 10) : d.u(0, s.pull_off_mm * 0.5);
  sensor_room = std::min(sensor_room, std::max(room_max, 0.0));
  const double away_room = d.u(0.5, 30);
  s.soft_limits_enable = d.chance(0.5);
  s.final_move_enable = d.chance(0.3);
  double final_away = d.u(-20, 20);
  if (pushing || shared) final_away = d.u(0, 20);
  final_away = std::max(final_away, -std::max(room_max, 0.0));
  if (s.soft_limits_enable) final_away = std::clamp(final_away, -sensor_room, away_room);
  // Machine coordinates: away from the sensor is -dir.
  const double lim_a = s.home_position_mm - dir * away_room, lim_b = s.home_position_mm + dir * sensor_room;
  s.soft_limit_min_mm = std::min(lim_a, lim_b);
  s.soft_limit_max_mm = std::max(lim_a, lim_b);
  s.final_position_mm = s.home_position_mm - dir * final_away;
  far_away = std::max({0.0, s.final_move_enable ? final_away : 0.0, s.soft_limits_enable ? away_room : 0.0});
  return sensor_room;
}

void Gen::place_switch(std::size_t a, double hyst_pair, double slack, bool shared, double& index_r) {
  AxisSettings& s = m.settings.axes[a];
  sim::AxisConfig& c = m.sim.axes[a];
  const double dir = dir_of(s);
  const double over = overshoot(s);
  const double hyst = std::max(c.hysteresis_mm, hyst_pair);
  s.max_backoff_mm += slack;
  const double edge_f = d.u(-50, 50);
  const bool pushing = mode_is_pushing(s.mode);
  // A pushing axis pushes its sensor's actuator against the mechanical stop
  // (placed within the push below): the cam reaches past the push, else the
  // carriage would leave the sensor's far side before it meets the stop.
  double cam_len = over + hyst + 2 * slack + d.u(0.5, 30);
  if (pushing) cam_len = std::max(cam_len, over + s.push_distance_mm + hyst + 1);
  // Off the sensor by more than a slave's start may differ from this one's.
  double gap = d.u(0.5, 25) + slack;
  if (!pushing && d.chance(0.15)) {
    const double depth_room = std::min(cam_len, s.max_backoff_mm - hyst - slack - 0.2) * 0.8;
    if (depth_room > 0.05) gap = -d.u(0, depth_room);
  }
  index_r = s.index_pitch_mm * d.u(0.15, 0.85);
  if (s.mode == HomingMode::switch_index) place_index(c, dir, s.index_pitch_mm, edge_f + c.hysteresis_mm, index_r);
  const double start_f = edge_f + gap;
  const double rest_f = reference_f(s, c, edge_f, index_r) + s.pull_off_mm;
  double far_away = 0;
  const double depth_max = std::min(cam_len - 1, 0.8 * (s.max_backoff_mm - hyst - slack - 0.2));
  const double sensor_room = limits(s, hyst, shared, rest_f - edge_f + depth_max, far_away);
  // The seek must reach the sensor from wherever a cycle may start: where a
  // final move, a jog or lost steps (3 mm) left it, from the rest point or
  // from the start (an unsequenced axis is assigned where it stands).
  const double farthest = std::max(gap, rest_f - edge_f) + far_away + 3;
  s.max_seek_travel_mm = std::max(farthest, 0.0) + s.pre_move_distance_mm + over + slack + d.u(1, 20);
  set_cam(a, dir, edge_f, cam_len, start_f);
  const double in_f = pushing ? edge_f - over - d.u(0, s.push_distance_mm * 0.8) - 1e-3
                              : std::min(edge_f - (std::abs(gap) + s.max_seek_travel_mm + over + 5),
                                         rest_f - sensor_room - 60);
  const double out_f = std::max(start_f, rest_f + far_away) + s.pre_move_distance_mm + s.max_backoff_mm + 120;
  set_stops(a, dir, in_f, out_f);
  m.plan[a].start_gap_mm = gap;
}

void Gen::still_axis(std::size_t a) {
  AxisSettings& s = m.settings.axes[a];
  sim::AxisConfig& c = m.sim.axes[a];
  draw_motion(s, c, PairDraw{});
  const double start = d.u(-50, 50);
  c.actual_position_mm = start;
  c.sensor_min_mm = start + d.u(200, 300);
  c.sensor_max_mm = c.sensor_min_mm + 10;
  c.hard_stop_min_mm = start - 200;
  c.hard_stop_max_mm = start + 500;
  c.absolute_offset_mm = 2 * s.home_position_mm - start + d.u(-5, 5);
  s.final_move_enable = d.chance(0.3);
  s.final_position_mm = s.home_position_mm + d.u(-20, 20);
  s.soft_limits_enable = (s.mode == HomingMode::manual || s.mode == HomingMode::drive) && d.chance(0.5);
  s.soft_limit_min_mm = std::min(s.home_position_mm, s.final_position_mm) - d.u(0.5, 30);
  s.soft_limit_max_mm = std::max(s.home_position_mm, s.final_position_mm) + d.u(0.5, 30);
  if (s.mode == HomingMode::absolute_final) {
    // The final move starts from what the encoder says.
    const double machine_now = start + c.absolute_offset_mm - s.home_position_mm;
    s.final_position_mm = machine_now + d.u(-20, 20);
  }
}

void Gen::hard_stop_axis(std::size_t a) {
  AxisSettings& s = m.settings.axes[a];
  sim::AxisConfig& c = m.sim.axes[a];
  draw_motion(s, c, PairDraw{});
  const double dir = s.direction == Direction::positive ? 1.0 : -1.0;
  // In the frame the stop lies at 0, the carriage starts above it.
  const double start_f = d.u(2, 60);
  c.actual_position_mm = mirror(dir, start_f);
  c.sensor_min_mm = 1;  // no cam: max below min
  c.sensor_max_mm = 0;
  set_stops(a, dir, 0, start_f + 500);
  c.stall_detect_ms = d.u(5, 40);
  c.stall_spread_ms = d.u(0, 20);
  const double pre = s.pre_move_mode == PreMove::always ? s.pre_move_distance_mm : 0;
  // Room for the stall's detection and the braking after it, lost against the stop.
  s.max_seek_travel_mm = start_f + pre + d.u(1, 30);
  const double latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
  s.stall_timeout_ms = (s.max_seek_travel_mm / latch_v * 1.2 + 1) * 1000;
  s.shared_limit = false;
  s.final_move_enable = d.chance(0.3);
  s.final_position_mm = s.home_position_mm - dir * d.u(0, 20);  // away from the stop
  // Soft limits that keep jogs and moves off the stop: its side just inside
  // the stop, between it and the home position.
  s.pull_off_mm = std::max(s.pull_off_mm, 0.2);
  const double stop_machine = s.home_position_mm + dir * s.pull_off_mm;
  s.soft_limits_enable = d.chance(0.5);
  const double near = stop_machine - dir * 0.1, far = s.home_position_mm - dir * d.u(25, 100);
  s.soft_limit_min_mm = std::min(near, far);
  s.soft_limit_max_mm = std::max(near, far);
}

// The drive's own home lies near the start, well inside the stops and off the
// cam; it answers within its time limit (late, up to most of the margin, one
// time in four), at its own speed.
void Gen::drive_axis(std::size_t a) {
  still_axis(a);
  AxisSettings& s = m.settings.axes[a];
  sim::AxisConfig& c = m.sim.axes[a];
  c.drive_home_position_mm = c.actual_position_mm + d.u(-40, 40);
  c.drive_speed_mm_per_min = d.u(300, 6000);
  // Wherever jogs, moves and lost steps leave the carriage, within its stops.
  const double reach_s = (c.hard_stop_max_mm - c.hard_stop_min_mm) / (c.drive_speed_mm_per_min / 60);
  const double margin_s = d.u(0.5, 3);
  // Never sooner than a homing can be (kDriveMinHomingTime_s), even from its own home.
  c.drive_answer_ms = 1000 * (d.chance(0.25) ? d.u(0.5, 0.9) * margin_s : d.u(kDriveMinHomingTime_s + 0.02, 0.3));
  s.drive_home_timeout_s = std::ceil(reach_s + c.drive_answer_ms / 1000 + margin_s);
}

void Gen::place_slave(std::size_t si, std::size_t mi, const PairDraw& pd, double budget, double slack,
                      double master_index_r) {
  const AxisSettings& ms = m.settings.axes[mi];
  const sim::AxisConfig& mc = m.sim.axes[mi];
  AxisSettings& s = m.settings.axes[si];
  sim::AxisConfig& c = m.sim.axes[si];
  AxisPlan& p = m.plan[si];
  const AxisSettings own = s;  // the slave's own values, drawn before the master's
  p.differs = d.chance(0.5);
  if (p.differs) {
    draw_motion(s, c, PairDraw{});
    // Its own mode only says it has a sensor of its own: any switch or
    // pushing mode (anything else is refused: slave_needs_sensor).
    s.mode = d.pick({HomingMode::switch_release, HomingMode::switch_reapproach, HomingMode::switch_index,
                     HomingMode::pushing_release, HomingMode::pushing_reapproach});
    s.max_seek_travel_mm = d.u(1, 300);
    s.soft_limits_enable = d.chance(0.5);
    s.soft_limit_min_mm = d.u(-100, 0);
    s.soft_limit_max_mm = d.u(0, 100);
    s.final_move_enable = d.chance(0.5);
    s.final_position_mm = d.u(-50, 50);
  } else {
    s = ms;
    s.kind = own.kind;  // what the axis is stays its own (X, Y, Z are linear only); its unit follows the master's
  }
  s.acceleration_mm_per_s2 = pd.accel;
  s.debounce_ms = pd.debounce_ms;
  s.max_misalignment_mm = pd.misalignment;
  s.slave_of = static_cast<std::uint8_t>(mi + 1);
  s.slave_mode = p.commutator ? SlaveMode::external_commutator : SlaveMode::own_output;
  s.sensor_nc = own.sensor_nc;
  s.pull_off_mm = own.pull_off_mm;
  s.switch_compensation_mm = own.switch_compensation_mm;
  s.shared_limit = own.shared_limit;
  c = sim::AxisConfig{};
  c.bounce_ms = pd.bounce_ms;
  c.hysteresis_mm = pd.hysteresis;
  c.noise_mm = d.chance(0.5) ? 0 : d.u(0, 0.01);
  c.sensor_nc = s.sensor_nc;
  if (p.commutator) m.sim.commutator_slave[mi] = static_cast<int>(si);

  const AxisSettings e = effective(m.settings, si);
  const double dir = dir_of(ms);
  const double edge_m_f = mirror(dir, m.plan[mi].cam_edge_mm);
  const double edge_f = edge_m_f + d.u(-20, 20);
  const double over = overshoot(ms);
  const double cam_len = over + pd.hysteresis + 2 * slack + d.u(0.5, 30);
  double index_r = master_index_r;
  if (ms.mode == HomingMode::switch_index) {
    index_r = std::clamp(master_index_r + d.u(-0.1, 0.1) * budget, 0.1 * ms.index_pitch_mm, 0.9 * ms.index_pitch_mm);
    place_index(c, dir, ms.index_pitch_mm, edge_f + c.hysteresis_mm, index_r);
  }
  const double start_m_f = mirror(dir, mc.actual_position_mm);
  const double rest_m_f = reference_f(ms, mc, edge_m_f, master_index_r) + ms.pull_off_mm;
  // A commutator slave squares on its own edge (no index of its own).
  AxisSettings sq = e;
  sq.mode = squaring_mode(m.settings, si);
  const double rest_f = reference_f(sq, c, edge_f, index_r) + e.pull_off_mm + e.switch_compensation_mm;
  p.skew_mm = p.bad_skew ? d.sign() * (1.3 * pd.misalignment + budget + d.u(0.3, 3)) : d.u(-1, 1) * budget;
  if (p.commutator && mode_is_pushing(ms.mode)) {
    // Trailing: the slave starts further from its edge than the master from its own.
    const double lead = (reference_f(sq, c, edge_f, index_r) - edge_f) - (reference_f(ms, mc, edge_m_f, master_index_r) - edge_m_f);
    p.skew_mm = std::min(0.0, lead) - std::abs(p.skew_mm);
  }
  const double start_f = start_m_f + (rest_f - rest_m_f) - p.skew_mm;
  p.rest_rel_mm = mirror(dir, rest_f) - mirror(dir, rest_m_f);
  p.budget_mm = budget;
  set_cam(si, dir, edge_f, cam_len, start_f);
  p.start_gap_mm = start_f - edge_f;
  double in_f = edge_f - (std::abs(p.start_gap_mm) + ms.max_seek_travel_mm + over + 2 * slack + 5);
  if (mode_is_pushing(ms.mode)) {
    // The slave's stop about as far behind its sensor as the master's. With
    // a commutator the slave rides on the master's output: its stop lies
    // where it is when the master reaches its own.
    const double m_stop_f = std::min(mirror(dir, mc.hard_stop_min_mm), mirror(dir, mc.hard_stop_max_mm));
    const double rides = p.commutator ? (start_f - start_m_f) - (edge_f - edge_m_f) : 0.0;
    // (Once square it no longer trails: the commutator slave's stop lies no nearer.)
    const double jitter = d.u(p.commutator ? 0.0 : -0.1, 0.1) * pd.misalignment;
    in_f = edge_f - std::max(over + 1e-3, (edge_m_f - m_stop_f) + std::max(0.0, -rides) + jitter);
  } else {
    const double m_in_f = std::min(mirror(dir, mc.hard_stop_min_mm), mirror(dir, mc.hard_stop_max_mm));
    in_f = std::min(in_f, m_in_f + (start_f - start_m_f) - slack - 5);
  }
  const double m_out_f = std::max(mirror(dir, mc.hard_stop_min_mm), mirror(dir, mc.hard_stop_max_mm));
  const double out_f = std::max(start_f + ms.pre_move_distance_mm + ms.max_backoff_mm + 120,
                                m_out_f + (start_f - start_m_f) + slack + 5);
  set_stops(si, dir, in_f, out_f);
}

void Gen::gantry(std::size_t mi, std::size_t si, bool commutator) {
  PairDraw pd;
  pd.pair = true;
  pd.accel = d.u(100, 2000);
  pd.debounce_ms = d.chance(0.5) ? 0 : d.u(0, 4);
  pd.bounce_ms = pd.debounce_ms > 1 && d.chance(0.5) ? d.u(0, pd.debounce_ms * 0.9) : 0;
  pd.hysteresis = d.u(0, 0.2);
  pd.misalignment = d.u(0.5, 5);
  AxisPlan& mp = m.plan[mi];
  AxisPlan& sp = m.plan[si];
  mp.role = Role::master;
  sp.role = Role::slave;
  mp.partner = static_cast<int>(si);
  sp.partner = static_cast<int>(mi);
  mp.commutator = sp.commutator = commutator;
  sp.bad_skew = d.chance(0.2);
  AxisSettings& ms = m.settings.axes[mi];
  AxisSettings& ss = m.settings.axes[si];
  // A gantry squares on its two sensors: no pushing master, with or without
  // a commutator (commutator_needs_switch_master).
  ms.mode = d.pick({HomingMode::switch_release, HomingMode::switch_reapproach, HomingMode::switch_index});
  const bool pushing = mode_is_pushing(ms.mode);
  ms.shared_limit = !pushing && d.chance(0.2);
  ss = AxisSettings{};
  ss.shared_limit = !pushing && d.chance(0.2);
  ss.sensor_nc = d.chance(0.3);
  ss.switch_compensation_mm = d.chance(0.5) ? 0 : d.u(-0.5, 0.5);
  draw_motion(ms, m.sim.axes[mi], pd);
  // A shared limit rests off its sensor: beyond the release hysteresis after
  // a reapproach, beyond the release point otherwise (for a slave: its
  // pull-off, the master's with a commutator, plus its compensation).
  const double shared_rest = mode_reapproaches(ms.mode) ? 0.35 : 0.1;
  if (ms.shared_limit) ms.pull_off_mm = std::max(ms.pull_off_mm, shared_rest);
  ss.pull_off_mm = d.chance(0.2) ? 0 : d.u(0.1, 3);
  if (ss.shared_limit) {
    if (commutator)
      ss.switch_compensation_mm = std::max(ss.switch_compensation_mm, shared_rest - ms.pull_off_mm);
    else
      ss.pull_off_mm = std::max(ss.pull_off_mm, shared_rest - ss.switch_compensation_mm);
  }
  // What the geometry needs on top of the skew: both sensors' hysteresis,
  // the pull-off and compensation difference, the stops' spread when
  // pushing, and for a commutator the slave's search back over the
  // master's pull-off past its own edge and its stop.
  const double seek_v = mm_per_min_to_mm_per_s(ms.seek_feedrate_mm_per_min);
  const double a_pair = std::min(ms.acceleration_mm_per_s2, pd.accel);
  // A side whose trigger falls in a late period is seen that period's travel
  // later: one side may stop that much further than the other.
  double extras = 2 * 0.2 + 0.05 + std::abs(ss.pull_off_mm + ss.switch_compensation_mm - ms.pull_off_mm) +
                  mm_per_min_to_mm_per_s(ms.seek_feedrate_mm_per_min) * m.max_dt_s;
  if (commutator) extras += ms.pull_off_mm + stop_distance_mm(seek_v, a_pair) + seek_v * m.max_dt_s + 0.2;
  // Widen the limit rather than squeeze the geometry.
  if (extras > 0.5 * pd.misalignment) pd.misalignment = extras / 0.5 * d.u(1.0, 1.5);
  if (pushing) extras += 0.2 * pd.misalignment;
  const double budget = std::max(0.0, 0.6 * pd.misalignment - extras);
  const double slack = budget + extras + (sp.bad_skew ? 1.3 * pd.misalignment + budget + 3 : 0);
  double index_r = 0;
  place_switch(mi, pd.hysteresis, slack, ms.shared_limit || ss.shared_limit, index_r);
  place_slave(si, mi, pd, budget, slack, index_r);
  sp.extras_mm = 2 * 0.2 + 0.05;
}

void Gen::roles_and_modes() {
  std::array<std::size_t, kAxisCount> order{0, 1, 2, 3, 4, 5};
  for (std::size_t i = kAxisCount - 1; i > 0; --i) std::swap(order[i], order[static_cast<std::size_t>(d.integer(0, static_cast<int>(i)))]);
  const int pairs = d.chance(0.4) ? 0 : (d.chance(0.75) ? 1 : 2);
  std::size_t next = 0;
  for (int p = 0; p < pairs; ++p) {
    const std::size_t mi = order[next++], si = order[next++];
    gantry(mi, si, d.chance(0.4));
  }
  for (; next < kAxisCount; ++next) {
    const std::size_t a = order[next];
    AxisSettings& s = m.settings.axes[a];
    s.mode = d.pick({HomingMode::disabled, HomingMode::manual, HomingMode::switch_release,
                     HomingMode::switch_release, HomingMode::switch_reapproach, HomingMode::switch_reapproach,
                     HomingMode::switch_index, HomingMode::absolute, HomingMode::absolute_final,
                     HomingMode::pushing_release, HomingMode::pushing_reapproach, HomingMode::hard_stop,
                     HomingMode::drive});
    if (s.mode == HomingMode::hard_stop) {
      hard_stop_axis(a);
    } else if (s.mode == HomingMode::drive) {
      drive_axis(a);
    } else if (mode_uses_switch(s.mode)) {
      s.shared_limit = !mode_is_pushing(s.mode) && d.chance(0.25);
      draw_motion(s, m.sim.axes[a], PairDraw{});
      if (s.shared_limit && mode_reapproaches(s.mode)) {
        // Resting off the sensor needs a pull-off beyond the release hysteresis.
        const auto& c = m.sim.axes[a];
        s.pull_off_mm = std::max(s.pull_off_mm, c.hysteresis_mm + 4 * c.noise_mm + 0.1);
      } else if (s.shared_limit) {
        s.pull_off_mm = std::max(s.pull_off_mm, 0.1);  // beyond the release point
      }
      double r = 0;
      place_switch(a, 0, 0, s.shared_limit, r);
    } else {
      still_axis(a);
    }
  }
}

void Gen::sequence() {
  auto& steps = m.settings.global.sequence_steps;
  steps.fill(0);
  const int n = d.integer(1, 6);
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisSettings& s = m.settings.axes[a];
    const auto step = [&] { return static_cast<std::size_t>(d.integer(0, n - 1)); };
    if (m.plan[a].role == Role::slave) {
      if (d.chance(0.3)) steps[step()] |= axis_bit(a);  // ignored
      continue;
    }
    if (s.mode == HomingMode::disabled) {
      if (d.chance(0.3)) steps[step()] |= axis_bit(a);
      continue;
    }
    if (d.chance(0.12)) continue;  // unsequenced
    steps[step()] |= axis_bit(a);
    if (d.chance(0.05)) steps[step()] |= axis_bit(a);
  }
}

// An unsequenced axis is assigned its home position where it stands, not at
// the rest point its soft limits were drawn around: where they would let a
// jog reach past a mechanical stop (no limit switch to stop it), the
// machine's builder would not have enabled them (seed 7316777: a pushing
// axis standing 1 mm off its stop, its soft limit 2 mm below). No dice: the
// other draws stay as they were.
void Gen::unsequenced_soft_limits() {
  AxisMask sequenced = 0;
  for (const AxisMask s : m.settings.global.sequence_steps) sequenced |= s;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisSettings& s = m.settings.axes[a];
    const sim::AxisConfig& c = m.sim.axes[a];
    if ((sequenced & axis_bit(a)) || m.plan[a].role == Role::slave || !s.soft_limits_enable || s.limits_fitted ||
        mode_is_absolute(s.mode) || (m.invalid != Invalid::none && m.invalid_axis == a))
      continue;  // (the axis drawn invalid keeps what makes it so)
    const double jog_v = mm_per_min_to_mm_per_s(s.jog_feedrate_mm_per_min);
    const double margin = stop_distance_mm(jog_v, s.acceleration_mm_per_s2) + jog_v * m.max_dt_s + 0.1;
    const double x0 = c.actual_position_mm;
    const double lo = x0 + (s.soft_limit_min_mm - s.home_position_mm);
    const double hi = x0 + (s.soft_limit_max_mm - s.home_position_mm);
    if (lo < c.hard_stop_min_mm + margin || hi > c.hard_stop_max_mm - margin) s.soft_limits_enable = false;
  }
}

// End-of-travel limit switches on plain switch-mode axes (no gantry, no
// shared limit, no pushing), with their own dice so that every other draw
// stays as it was: the switches where the stops were drawn (beyond anything
// a cycle, jog or move of this machine reaches), NO or NC, an overtravel the
// rule limit_overtravel_too_short accepts, the stops moved out past it.
void Gen::limit_switches() {
  Dice lim(m.seed, 11);  // 7: indexers; 2, 3, 8: the run's own
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisSettings& s = m.settings.axes[a];
    bool linked = s.slave_of != 0;
    for (const AxisSettings& o : m.settings.axes) linked = linked || o.slave_of == a + 1;
    const bool eligible = m.plan[a].role == Role::plain && !linked && !s.shared_limit &&
                          (s.mode == HomingMode::switch_release || s.mode == HomingMode::switch_reapproach ||
                           s.mode == HomingMode::switch_index);
    // Not the axis made wrong on purpose: its own refusal must stay the one expected.
    if (!eligible || (m.invalid != Invalid::none && m.invalid_axis == a) || !lim.chance(0.3)) continue;
    sim::AxisConfig& c = m.sim.axes[a];
    s.limits_fitted = true;
    s.limits_nc = c.limits_nc = lim.chance(0.4);
    s.limit_overtravel_mm = limit_stop_distance_mm(s) * lim.u(1.05, 2.0) + lim.u(0.1, 5);
    c.limit_min_mm = c.hard_stop_min_mm;
    c.limit_max_mm = c.hard_stop_max_mm;
    c.hard_stop_min_mm = c.limit_min_mm - s.limit_overtravel_mm - lim.u(0, 2);
    c.hard_stop_max_mm = c.limit_max_mm + s.limit_overtravel_mm + lim.u(0, 2);
    m.plan[a].limits = true;
    // Both switches stuck active from power-up (limits_stuck), on an axis no
    // event of the first cycle gives another fault.
    bool evented = false;
    for (const Event& e : m.events) evented = evented || e.axis == a;
    if (m.plan[a].start_fault == sim::Fault::none && !evented && lim.chance(0.15)) {
      m.plan[a].start_fault = sim::Fault::limits_stuck;
      c.fault = sim::Fault::limits_stuck;
    }
  }
}

// Hard-stop axes that read their encoder for the stop (stall_detect
// following_error), with their own dice so that every other draw stays as it
// was: a limit the rule following_error_in_noise accepts, mostly within the
// push's travel beyond the stop, one in ten beyond it (stop_not_found); an
// encoder counting in steps of up to 1 um with noise within what the rule
// allows for; now and then an encoder reversed from power-up or reporting no
// valid position. A stall output made dead or stuck on by causes() stays:
// the encoder must home the axis all the same.
void Gen::following_error() {
  Dice fe(m.seed, 12);  // every stream and what it draws: dice.hpp
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisSettings& s = m.settings.axes[a];
    AxisPlan& p = m.plan[a];
    if (s.mode != HomingMode::hard_stop || p.role != Role::plain || p.encoder_invalid) continue;
    if ((m.invalid != Invalid::none && m.invalid_axis == a) || !fe.chance(0.5)) continue;
    sim::AxisConfig& c = m.sim.axes[a];
    s.stall_detect = StallDetect::following_error;
    const double stop = s.direction == Direction::negative ? c.hard_stop_min_mm : c.hard_stop_max_mm;
    const double pre = s.pre_move_mode == PreMove::always ? s.pre_move_distance_mm : 0;
    // The push's travel left beyond the stop from where the first cycle starts (at least 1 mm).
    const double room = s.max_seek_travel_mm - std::abs(c.actual_position_mm - stop) - pre;
    const double floor = following_error_floor_mm(s);
    s.max_following_error_mm = fe.chance(0.1) ? std::min(room * fe.u(1.1, 2.0), s.max_seek_travel_mm * 0.95)
                                              : floor * fe.u(1.2, 4.0) + (fe.chance(0.5) ? fe.u(0, 0.5 * room) : 0.0);
    s.max_following_error_mm = std::max(s.max_following_error_mm, floor * 1.05);
    c.encoder_resolution_mm = fe.chance(0.5) ? fe.u(0, 0.001) : 0;
    c.encoder_noise_mm = fe.chance(0.5) ? fe.u(0, 0.0003) : 0;
    p.following_error = true;
    bool evented = false;
    for (const Event& e : m.events) evented = evented || e.axis == a;
    if (p.start_fault == sim::Fault::none && !evented && fe.chance(0.1)) {
      p.start_fault = c.fault = sim::Fault::encoder_reversed;
    } else if (fe.chance(0.05)) {
      p.encoder_invalid = true;
    }
  }
}

// Reference checks and commissioning measurements (service_acts.cpp), with
// their own dice (stream 17) so that every other draw stays as it was:
// every axis's refcheck_tolerance (half the time the register's default
// 0.1 mm, else 0.02 to 1 mm: well above the edge's noise and the period's
// error, so a carriage left where it stopped is always accepted); and on
// some plain hard-stop axes that tell their stop by the drive's stall input,
// the far stop pulled in from 500 mm to just beyond everything a run of this
// machine reaches (the soft limit on that side drawn within 5 to 25 mm of
// the home position for it), mostly with a max_seek_travel that reaches it
// and now and then one that does not (the measurement's
// travel_end_not_found), so that a measurement travels seconds, not minutes,
// at latch feedrate.
void Gen::travel_ends() {
  Dice te(m.seed, 17);
  AxisMask sequenced = 0;
  for (const AxisMask st : m.settings.global.sequence_steps) sequenced |= st;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisSettings& s = m.settings.axes[a];
    s.refcheck_tolerance_mm = te.chance(0.5) ? 0.1 : te.u(0.02, 1.0);
    const AxisPlan& p = m.plan[a];
    const bool eligible = s.mode == HomingMode::hard_stop && s.stall_detect == StallDetect::stall_input &&
                          p.role == Role::plain && p.start_fault == sim::Fault::none && !p.encoder_invalid &&
                          (sequenced & axis_bit(a)) && !(m.invalid != Invalid::none && m.invalid_axis == a);
    if (!eligible || !te.chance(0.5)) continue;
    sim::AxisConfig& c = m.sim.axes[a];
    const double dir = dir_of(s);
    // In the frame: the home stop at 0, distances away from it.
    const double home_stop = dir < 0 ? c.hard_stop_min_mm : c.hard_stop_max_mm;
    const double start_f = (c.actual_position_mm - home_stop) * -dir;
    const double extent = te.u(5, 25);
    if (dir < 0) s.soft_limit_max_mm = s.home_position_mm + extent;
    else s.soft_limit_min_mm = s.home_position_mm - extent;
    s.final_position_mm = s.home_position_mm - dir * te.u(0, 0.9 * extent);
    const double jog_v = mm_per_min_to_mm_per_s(s.jog_feedrate_mm_per_min);
    const double jog_margin = stop_distance_mm(jog_v, s.acceleration_mm_per_s2) + jog_v * m.max_dt_s + 0.5;
    // A pre-move "always" runs at the start of every cycle, homed or not: a
    // cycle stopped by an alarm after it leaves the carriage that much nearer
    // the far stop, and the next one pre-moves again from there (seed
    // 188007005: a second pre-move of 4.8 mm met a stop 20 mm out). A run
    // starts at most kCyclesPerRun cycles: the first, then up to four
    // follow-up acts of at most two each (a measurement's, then a cycle of
    // the act drawn; or a recovery's).
    constexpr int kCyclesPerRun = 9;
    const double pre = s.pre_move_mode == PreMove::always ? kCyclesPerRun * s.pre_move_distance_mm : 0;
    // A jog and a move before homing (3 mm beyond the start), jogs and moves
    // up to the soft limit, the final move within it.
    const double reach_f = std::max(start_f + pre + 3, s.pull_off_mm + extent + jog_margin);
    const double far_f = reach_f + te.u(1, 15);
    if (dir < 0) c.hard_stop_max_mm = home_stop + far_f;
    else c.hard_stop_min_mm = home_stop - far_f;
    // From the rest point the measurement meets the stop within far_f; the
    // motor runs on until the stall is read, then brakes.
    const double latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
    const double run_on = latch_v * ((c.stall_detect_ms + c.stall_spread_ms) / 1000 + 2 * m.max_dt_s) +
                          stop_distance_mm(latch_v, s.acceleration_mm_per_s2);
    if (te.chance(0.85)) s.max_seek_travel_mm = std::max(s.max_seek_travel_mm, far_f + run_on + te.u(1, 10));
    s.stall_timeout_ms = (s.max_seek_travel_mm / latch_v * 1.2 + 1) * 1000;
    m.plan[a].far_stop_near = true;
  }
}

// The failure policy (global.failure_policy), with its own dice so that
// every other draw stays as it was: each of the three as often.
void Gen::failure_policy() {
  Dice fp(m.seed, 30);  // 7: indexers; 11: limit switches; 12: following error; 2, 3, 8: the run's own
  m.settings.global.failure_policy =
      fp.pick({FailurePolicy::stop_all, FailurePolicy::finish_independent, FailurePolicy::return_to_start});
}

Machine Gen::build() {
  // One period in ten comes late, by up to the 20 ms the README promises.
  m.max_dt_s = d.chance(0.3) ? 0.002 : d.u(0.005, 0.020);
  for (auto& c : m.sim.axes) c = sim::AxisConfig{};
  roles_and_modes();
  sequence();
  GlobalSettings& g = m.settings.global;
  g.alarm_clears_homed = d.chance(0.5);
  g.allowed_without_homing = d.chance(0.6) ? AllowedWithoutHoming::all
                             : d.chance(0.5) ? AllowedWithoutHoming::jog_reduced
                                             : AllowedWithoutHoming::none;
  g.permit_required = d.chance(0.2);
  m.sim.seed = m.seed;
  causes();
  events();
  indexers();
  limit_switches();
  following_error();
  home_cams();
  limits_in_reach();
  travel_ends();
  failure_policy();
  unsequenced_soft_limits();
  m.start_held_at_powerup = d.chance(0.15);
  m.powerup_periods = d.integer(1, 50);
  m.start_by_button = d.chance(0.25);
  return m;
}

}  // namespace gen

Machine generate(std::uint64_t seed) { return gen::Gen(seed).build(); }

}  // namespace campaign
