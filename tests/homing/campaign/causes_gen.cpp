// What the generator makes go wrong: settings the configuration check must
// refuse, a short cam, a shared limit resting on its sensor, a sensor fault
// from power-up, an invalid encoder, and the events of the first cycle.
#include <algorithm>
#include <cmath>

#include "gen.hpp"
#include "homing/motion.hpp"

namespace campaign {
namespace gen {

std::vector<std::size_t> Gen::axes_where(const std::function<bool(std::size_t)>& pred) const {
  std::vector<std::size_t> out;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (pred(a)) out.push_back(a);
  return out;
}

bool Gen::is_switch_axis(std::size_t a) const {
  return m.plan[a].role != Role::slave && mode_uses_switch(m.settings.axes[a].mode);
}

void Gen::invalid_settings() {
  const auto kind = static_cast<Invalid>(d.integer(1, static_cast<int>(Invalid::count) - 1));
  Settings& st = m.settings;
  std::size_t a = 0;
  const CyclePlan plan = plan_cycle(st, true, 0);
  switch (kind) {
    case Invalid::zero_acceleration:
      if (!pick_axis(axes_where([&](std::size_t x) { return is_switch_axis(x) && m.plan[x].role == Role::plain; }), a)) return;
      st.axes[a].acceleration_mm_per_s2 = 0;
      break;
    case Invalid::latch_not_slower:
      if (!pick_axis(axes_where([&](std::size_t x) { return is_switch_axis(x); }), a)) return;
      st.axes[a].latch_feedrate_mm_per_min = st.axes[a].seek_feedrate_mm_per_min * d.u(1, 1.5);
      break;
    case Invalid::stop_distance_short:
      if (!pick_axis(axes_where([&](std::size_t x) { return is_switch_axis(x); }), a)) return;
      st.axes[a].max_stop_distance_mm = seek_stop_distance_mm(effective(st, a)) * d.u(0.1, 0.9);
      break;
    case Invalid::push_beyond_backoff:
      if (!pick_axis(axes_where([&](std::size_t x) { return is_switch_axis(x) && mode_is_pushing(st.axes[x].mode); }), a)) return;
      st.axes[a].push_distance_mm = st.axes[a].max_backoff_mm * d.u(1.05, 2);
      break;
    case Invalid::no_index_pitch:
      if (!pick_axis(axes_where([&](std::size_t x) { return is_switch_axis(x) && st.axes[x].mode == HomingMode::switch_index; }), a)) return;
      st.axes[a].index_pitch_mm = 0;
      break;
    case Invalid::soft_limits_inverted:
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role != Role::slave && st.axes[x].mode != HomingMode::disabled; }), a)) return;
      st.axes[a].soft_limits_enable = true;
      std::swap(st.axes[a].soft_limit_min_mm, st.axes[a].soft_limit_max_mm);
      if (st.axes[a].soft_limit_min_mm < st.axes[a].soft_limit_max_mm) return;
      break;
    case Invalid::home_outside_soft_limits:
      if (!pick_axis(axes_where([&](std::size_t x) { return is_switch_axis(x) && (plan.covered & axis_bit(x)); }), a)) return;
      st.axes[a].soft_limits_enable = true;
      st.axes[a].home_position_mm = st.axes[a].soft_limit_max_mm + d.u(0.1, 10);
      break;
    case Invalid::unsequenced_home_outside_soft_limits:
      if (!pick_axis(axes_where([&](std::size_t x) {
            return (plan.unsequenced & axis_bit(x)) && m.plan[x].role != Role::slave &&
                   !mode_is_absolute(st.axes[x].mode);
          }), a)) return;
      st.axes[a].soft_limits_enable = true;
      st.axes[a].home_position_mm = st.axes[a].soft_limit_min_mm - d.u(0.1, 10);
      break;
    case Invalid::slave_of_disabled: {
      std::size_t target = 0;
      if (!pick_axis(axes_where([&](std::size_t x) { return st.axes[x].mode == HomingMode::disabled; }), target)) return;
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::plain && x != target; }), a)) return;
      st.axes[a].slave_of = static_cast<std::uint8_t>(target + 1);
      break;
    }
    case Invalid::slave_of_slave: {
      std::size_t target = 0;
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::slave; }), target)) return;
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::plain && is_switch_axis(x); }), a)) return;
      st.axes[a].slave_of = static_cast<std::uint8_t>(target + 1);
      break;
    }
    case Invalid::two_slaves: {
      std::size_t target = 0;
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::master; }), target)) return;
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::plain && is_switch_axis(x); }), a)) return;
      st.axes[a].slave_of = static_cast<std::uint8_t>(target + 1);
      st.axes[a].max_misalignment_mm = 2;
      break;
    }
    case Invalid::master_not_on_switch: {
      std::size_t target = 0;
      if (!pick_axis(axes_where([&](std::size_t x) {
            return m.plan[x].role == Role::plain && (st.axes[x].mode == HomingMode::manual || mode_is_absolute(st.axes[x].mode));
          }), target)) return;
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::plain && is_switch_axis(x); }), a)) return;
      st.axes[a].slave_of = static_cast<std::uint8_t>(target + 1);
      st.axes[a].max_misalignment_mm = 2;
      break;
    }
    case Invalid::slave_of_itself:
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::plain && is_switch_axis(x); }), a)) return;
      st.axes[a].slave_of = static_cast<std::uint8_t>(a + 1);
      break;
    case Invalid::slave_disabled:
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::slave; }), a)) return;
      st.axes[a].mode = HomingMode::disabled;
      break;
    case Invalid::gantry_stop_beyond_misalignment: {
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::slave; }), a)) return;
      const AxisSettings e = effective(st, a);
      const double v = mm_per_min_to_mm_per_s(std::max(e.seek_feedrate_mm_per_min, e.jog_feedrate_mm_per_min));
      st.axes[a].max_misalignment_mm = stop_distance_mm(v, e.acceleration_mm_per_s2) * d.u(0.2, 0.9);
      break;
    }
    case Invalid::pushing_master:
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::master; }), a)) return;
      st.axes[a].mode = d.pick({HomingMode::pushing_release, HomingMode::pushing_reapproach});
      st.axes[a].max_backoff_mm += st.axes[a].push_distance_mm;
      break;
    case Invalid::slave_without_sensor:
      if (!pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::slave; }), a)) return;
      st.axes[a].mode = d.pick({HomingMode::manual, HomingMode::absolute, HomingMode::absolute_final});
      break;
    case Invalid::shared_limit_on_sensor:
      if (!pick_axis(axes_where([&](std::size_t x) { return is_switch_axis(x) && !mode_is_pushing(st.axes[x].mode); }), a)) return;
      st.axes[a].shared_limit = true;
      st.axes[a].pull_off_mm = 0;
      break;
    case Invalid::drive_without_time_limit:
      if (!pick_axis(axes_where([&](std::size_t x) { return st.axes[x].mode == HomingMode::drive; }), a)) return;
      st.axes[a].drive_home_timeout_s = 0;
      break;
    case Invalid::none:
    case Invalid::count:
      return;
  }
  m.invalid = kind;
  m.invalid_axis = a;
}

void Gen::causes() {
  if (d.chance(0.12)) invalid_settings();
  // A cam shorter than the seek's stop, on a plain axis starting off it.
  if (d.chance(0.05)) {
    std::size_t a = 0;
    if (pick_axis(axes_where([&](std::size_t x) {
          return m.plan[x].role == Role::plain && is_switch_axis(x) && !mode_is_pushing(m.settings.axes[x].mode) &&
                 m.plan[x].start_gap_mm > 0 && !m.settings.axes[x].shared_limit;
        }), a)) {
      const AxisSettings& s = m.settings.axes[a];
      sim::AxisConfig& c = m.sim.axes[a];
      const double stop = stop_distance_mm(mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min), s.acceleration_mm_per_s2);
      c.hysteresis_mm = std::min(c.hysteresis_mm, 0.3 * stop);
      c.noise_mm = 0;
      const double len = (stop - c.hysteresis_mm) * d.u(0.1, 0.6);
      const double dir = dir_of(s);
      const double edge_f = mirror(dir, m.plan[a].cam_edge_mm);
      const double p = mirror(dir, edge_f), q = mirror(dir, edge_f - len);
      c.sensor_min_mm = std::min(p, q);
      c.sensor_max_mm = std::max(p, q);
      m.plan[a].short_cam = true;
    }
  }
  // A shared limit that rests on its own sensor after pull-off.
  if (d.chance(0.03)) {
    std::size_t a = 0;
    if (pick_axis(axes_where([&](std::size_t x) {
          // Not the axis made invalid on purpose: a pull-off here would make it valid again (seed 8032843).
          return m.plan[x].role == Role::plain && is_switch_axis(x) && mode_reapproaches(m.settings.axes[x].mode) &&
                 !mode_is_pushing(m.settings.axes[x].mode) && m.sim.axes[x].hysteresis_mm > 0.02 &&
                 (m.invalid == Invalid::none || x != m.invalid_axis);
        }), a)) {
      AxisSettings& s = m.settings.axes[a];
      s.shared_limit = true;
      // Off its edge by less than the hysteresis: the check accepts it (a
      // pull-off of 0 it refuses: Invalid::shared_limit_on_sensor).
      s.pull_off_mm = d.u(0.1, 0.5) * m.sim.axes[a].hysteresis_mm;
      s.final_move_enable = false;
      m.plan[a].rest_on_sensor = true;
    }
  }
  // A sensor fault from power-up.
  if (d.chance(0.08)) {
    std::size_t a = 0;
    if (pick_axis(axes_where([&](std::size_t x) { return mode_uses_switch(effective(m.settings, x).mode); }), a)) {
      m.plan[a].start_fault = d.pick({sim::Fault::sensor_stuck_active, sim::Fault::sensor_stuck_inactive, sim::Fault::wire_break});
      m.sim.axes[a].fault = m.plan[a].start_fault;
    }
  }
  // A drive's stall output dead or stuck on from power-up (hard-stop homing).
  if (d.chance(0.15)) {
    std::size_t a = 0;
    if (pick_axis(axes_where([&](std::size_t x) { return m.settings.axes[x].mode == HomingMode::hard_stop; }), a)) {
      m.plan[a].start_fault = d.pick({sim::Fault::stall_dead, sim::Fault::stall_stuck});
      m.sim.axes[a].fault = m.plan[a].start_fault;
    }
  }
  // A drive that homes itself gone wrong: it never answers, answers at once,
  // has lost its home done, or answers after its time limit.
  if (d.chance(0.12)) {
    std::size_t a = 0;
    if (pick_axis(axes_where([&](std::size_t x) { return m.settings.axes[x].mode == HomingMode::drive; }), a)) {
      const int kind = d.integer(0, 3);
      if (kind == 3) {
        m.sim.axes[a].drive_answer_ms = 1000 * (m.settings.axes[a].drive_home_timeout_s + d.u(0.5, 3));
        m.plan[a].late_drive = true;
      } else {
        m.plan[a].start_fault = kind == 0   ? sim::Fault::drive_never_answers
                                : kind == 1 ? sim::Fault::drive_answers_at_once
                                            : sim::Fault::drive_done_lost;
        m.sim.axes[a].fault = m.plan[a].start_fault;
      }
    }
  }
  // An absolute encoder that reports no valid position.
  if (d.chance(0.05)) {
    std::size_t a = 0;
    if (pick_axis(axes_where([&](std::size_t x) { return m.plan[x].role == Role::plain && mode_is_absolute(m.settings.axes[x].mode); }), a))
      m.plan[a].encoder_invalid = true;
  }
}

double Gen::axis_time_estimate(std::size_t a) const {
  const AxisSettings e = effective(m.settings, a);
  if (e.mode == HomingMode::hard_stop) {
    const sim::AxisConfig& c = m.sim.axes[a];
    const double stop = e.direction == Direction::negative ? c.hard_stop_min_mm : c.hard_stop_max_mm;
    const double latch_v = mm_per_min_to_mm_per_s(e.latch_feedrate_mm_per_min);
    return (std::abs(c.actual_position_mm - stop) + e.pre_move_distance_mm) / latch_v + 1.0 +
           (final_move_wanted(e) ? 2.0 : 0.0);
  }
  if (e.mode == HomingMode::drive) {
    const sim::AxisConfig& c = m.sim.axes[a];
    return std::abs(c.drive_home_position_mm - c.actual_position_mm) / (c.drive_speed_mm_per_min / 60) +
           c.drive_answer_ms / 1000 + (final_move_wanted(e) ? 2.0 : 0.0);
  }
  if (!mode_uses_switch(e.mode)) return final_move_wanted(e) ? 2.0 : 0.0;
  const double seek_v = mm_per_min_to_mm_per_s(e.seek_feedrate_mm_per_min);
  const double latch_v = mm_per_min_to_mm_per_s(e.latch_feedrate_mm_per_min);
  const double gap = std::abs(m.plan[a].start_gap_mm) + e.pre_move_distance_mm;
  double t = gap / seek_v + 2 * (e.max_stop_distance_mm + 0.5) / latch_v + e.pull_off_mm / seek_v;
  if (mode_is_pushing(e.mode)) t += e.push_distance_mm / latch_v;
  if (e.mode == HomingMode::switch_index) t += e.index_pitch_mm / latch_v;
  return t + (final_move_wanted(e) ? 2.0 : 0.0);
}

void Gen::events() {
  const CyclePlan plan = plan_cycle(m.settings, true, 0);
  double total = 0;
  for (int step = 1; step <= 6; ++step) {
    double longest = 0;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (plan.step[a] == step) longest = std::max(longest, axis_time_estimate(a) * (m.plan[a].commutator ? 2 : 1));
    total += longest;
  }
  m.cycle_estimate_s = std::max(total, 0.1);
  if (!d.chance(0.45)) return;
  const int n = d.chance(0.8) ? 1 : 2;
  for (int i = 0; i < n; ++i) {
    Event e;
    e.kind = static_cast<EventKind>(d.integer(0, kCommonEventKinds - 1));
    e.at_s = d.u(0, m.cycle_estimate_s);
    std::size_t a = 0;
    const bool sensor = e.kind == EventKind::stuck_active || e.kind == EventKind::stuck_inactive ||
                        e.kind == EventKind::wire_break;
    if (sensor) {
      if (!pick_axis(axes_where([&](std::size_t x) { return plan.movers & axis_bit(x) && mode_uses_switch(effective(m.settings, x).mode); }), a)) continue;
    } else if (e.kind == EventKind::drive_fault) {
      if (!pick_axis(axes_where([&](std::size_t x) { return plan.movers & axis_bit(x); }), a)) continue;
    } else if (e.kind == EventKind::drive_done_lost) {
      if (!pick_axis(axes_where([&](std::size_t x) { return m.settings.axes[x].mode == HomingMode::drive; }), a)) continue;
    }
    e.axis = a;
    if (e.kind == EventKind::permit_off) m.settings.global.permit_required = true;
    m.events.push_back(e);
  }
}

// Locking indexers on plain axes no slave_of names either way (a gantry may
// not have one: indexer_in_gantry), with their own dice so that the rest of
// the machine draws as before: pin delays up to 30 ms, a timeout of 60 to
// 400 ms, now and then a fault from power-up or during the first cycle.
void Gen::indexers() {
  Dice ix(m.seed, 7);
  const CyclePlan plan = plan_cycle(m.settings, true, 0);
  std::vector<std::size_t> fitted;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisSettings& s = m.settings.axes[a];
    bool linked = s.slave_of != 0;
    for (const AxisSettings& o : m.settings.axes) linked = linked || o.slave_of == a + 1;
    if (m.plan[a].role != Role::plain || linked || s.shared_limit || !ix.chance(0.25)) continue;
    s.indexer_lock = true;
    s.lock_timeout_ms = ix.u(60, 400);
    m.sim.indexer[a] = true;
    m.sim.axes[a].unlock_delay_ms = ix.u(0, 30);
    m.sim.axes[a].lock_delay_ms = ix.u(0, 30);
    m.plan[a].indexer = true;
    if (m.plan[a].start_fault == sim::Fault::none && ix.chance(0.12)) {
      m.plan[a].start_fault = ix.pick({sim::Fault::indexer_stuck_locked, sim::Fault::indexer_never_locks});
      m.sim.axes[a].fault = m.plan[a].start_fault;
    }
    if ((plan.movers & axis_bit(a)) && m.plan[a].start_fault == sim::Fault::none) fitted.push_back(a);
  }
  if (fitted.empty() || !ix.chance(0.35)) return;
  Event e;
  e.kind = ix.pick({EventKind::indexer_stuck_locked, EventKind::indexer_never_locks});
  e.axis = fitted[static_cast<std::size_t>(ix.integer(0, static_cast<int>(fitted.size()) - 1))];
  e.at_s = ix.u(0, m.cycle_estimate_s);
  m.events.push_back(e);
}

}  // namespace gen

const char* invalid_name(Invalid v) {
  static const char* names[] = {"none",
                                "zero acceleration",
                                "latch feedrate not slower than seek",
                                "max stop distance shorter than the stop",
                                "push distance beyond max back-off",
                                "index mode without index pitch",
                                "soft limits inverted",
                                "home position outside the soft limits",
                                "unsequenced axis's home position outside its soft limits",
                                "slave of a disabled axis",
                                "slave of a slave",
                                "two slaves on one master",
                                "master that does not home on a switch",
                                "slave of itself",
                                "disabled slave",
                                "gantry stop distance beyond max misalignment",
                                "gantry master in a pushing mode",
                                "slave without a sensor of its own",
                                "shared limit resting on its sensor (no pull-off)",
                                "drive-performed homing without a time limit"};
  return names[static_cast<int>(v)];
}

const char* event_name(EventKind k) {
  static const char* names[] = {"abort", "e-stop", "drive fault", "sensor stuck active", "sensor stuck inactive",
                                "wire break", "communication lost", "permit off", "reset", "home again",
                                "drive's home done lost", "indexer stuck locked", "indexer never locks"};
  return names[static_cast<int>(k)];
}

}  // namespace campaign

