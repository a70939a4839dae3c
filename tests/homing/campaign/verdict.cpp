#include "verdict.hpp"

#include <sstream>

#include "homing/motion.hpp"

namespace campaign {

void Causes::sensor_fault() {
  allow({AlarmCode::sensor_not_found, AlarmCode::overrun_during_stop, AlarmCode::stop_distance_exceeded,
         AlarmCode::not_released, AlarmCode::reapproach_not_found, AlarmCode::index_not_found,
         AlarmCode::misalignment, AlarmCode::slave_sensor_missing, AlarmCode::hard_limit});
}

std::string alarm_list(std::uint32_t bits) {
  std::string out;
  for (unsigned c = 1; c < kAlarmCodeCount; ++c)
    if (bits & (1u << c)) out += (out.empty() ? "" : ", ") + std::string(alarm_name(static_cast<AlarmCode>(c)));
  return out.empty() ? "none" : out;
}

Causes standing_causes(rig::Rig& r, const Machine& m, const CyclePlan& plan, bool refused, AxisMask encoder_invalid) {
  Causes c;
  if (refused) {
    c.allow({AlarmCode::settings_fault, AlarmCode::slave_sensor_missing});
    c.must.push_back("the configuration check's refusal");
    return c;
  }
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisMask bit = axis_bit(a);
    const AxisPlan& p = m.plan[a];
    const bool mover = plan.movers & bit;
    const AxisSettings e = effective(r.settings, a);
    const sim::Fault f = r.sim().axis_config(a).fault;
    if (f == sim::Fault::sensor_stuck_active || f == sim::Fault::sensor_stuck_inactive || f == sim::Fault::wire_break) {
      c.sensor_fault();
      if (mover && mode_uses_switch(e.mode)) c.must.push_back(std::string(1, kAxisUpper[a]) + "'s faulty sensor");
    }
    if (p.short_cam) {
      c.allow({AlarmCode::overrun_during_stop, AlarmCode::sensor_not_found});
      if (mover) c.must.push_back(std::string(1, kAxisUpper[a]) + "'s cam shorter than its stop");
    }
    if (p.rest_on_sensor) c.allow({AlarmCode::settings_fault, AlarmCode::not_released});
    // A cycle that starts deeper in the cam than max_backoff can release (a
    // jog or move left it there) backs off straight away and must give up.
    if (mover && mode_uses_switch(e.mode) && f == sim::Fault::none) {
      const auto& cfg = r.sim().axis_config(a);
      const double x = r.actual(a);
      const double depth = dir_of(e) < 0 ? cfg.sensor_max_mm - x : x - cfg.sensor_min_mm;
      const bool inside = x >= cfg.sensor_min_mm && x <= cfg.sensor_max_mm;
      if (inside && depth + cfg.hysteresis_mm + 4 * cfg.noise_mm >= e.max_backoff_mm)
        c.allow({AlarmCode::not_released});
    }
    // An unsequenced shared-limit axis is assigned where it stands: on its sensor, that is a trip.
    if ((plan.unsequenced & bit) && r.settings.axes[a].shared_limit) c.allow({AlarmCode::hard_limit});
    if (p.role == Role::slave && mover) {
      // The skew from where this cycle starts (earlier cycles may have racked
      // the pair within its limit, squarer or less square).
      const std::size_t mi = static_cast<std::size_t>(p.partner);
      const double skew = std::abs(p.rest_rel_mm - (r.actual(a) - r.actual(mi)));
      const double limit = r.settings.axes[a].max_misalignment_mm;
      if (p.bad_skew || skew > p.budget_mm + 1e-3)
        c.allow({AlarmCode::misalignment, AlarmCode::not_released, AlarmCode::sensor_not_found,
                 AlarmCode::slave_sensor_missing});
      if (skew > limit + p.extras_mm)
        c.must.push_back(std::string(1, kAxisUpper[a]) + "'s skew beyond its max misalignment");
    }
    if ((encoder_invalid & bit) && mode_is_absolute(e.mode)) {
      c.allow({AlarmCode::encoder_fault});
      if ((plan.covered & bit) || (plan.unsequenced & bit))
        c.must.push_back(std::string(1, kAxisUpper[a]) + "'s invalid absolute encoder");
    }
  }
  return c;
}

void event_cause(Causes& c, const Event& e, const Settings& s) {
  const std::string who = std::string(event_name(e.kind)) + " on " + kAxisUpper[e.axis];
  switch (e.kind) {
    case EventKind::abort: c.allow({AlarmCode::aborted}); c.must.push_back("the abort"); break;
    case EventKind::estop: c.allow({AlarmCode::emergency_stop}); c.must.push_back("the e-stop"); break;
    case EventKind::drive_fault: c.allow({AlarmCode::drive_fault}); c.must.push_back(who); break;
    case EventKind::stuck_active:
    case EventKind::stuck_inactive:
    case EventKind::wire_break: c.sensor_fault(); break;
    case EventKind::comm_lost: c.allow({AlarmCode::communication_lost}); break;
    case EventKind::permit_off:
      c.allow({AlarmCode::permit_withdrawn});
      if (s.global.permit_required) c.must.push_back("the permit withdrawn");
      break;
    case EventKind::reset:
    case EventKind::home_again:
    case EventKind::count: break;
  }
}

double path_bound(rig::Rig& r, const Machine& m, std::size_t a, double x_start) {
  const AxisSettings e = effective(r.settings, a);
  const double seek_v = mm_per_min_to_mm_per_s(e.seek_feedrate_mm_per_min);
  const double latch_v = mm_per_min_to_mm_per_s(e.latch_feedrate_mm_per_min);
  const double acc = e.acceleration_mm_per_s2;
  const double stop = acc > 0 ? stop_distance_mm(seek_v, acc) + seek_v * m.max_dt_s : 0;
  double final_d = 0;
  if (final_move_wanted(e)) {
    final_d = std::abs(e.final_position_mm - e.home_position_mm);
    if (mode_is_absolute(e.mode)) {
      const auto& c = r.sim().axis_config(a);
      final_d = std::abs(e.final_position_mm - (x_start + c.absolute_offset_mm - e.home_position_mm));
    }
  }
  if (!mode_uses_switch(e.mode)) return final_d + stop + 1e-6;
  const double over = e.max_stop_distance_mm + seek_v * m.max_dt_s + 1e-3;
  const double index = e.mode == HomingMode::switch_index ? e.index_pitch_mm * 1.1 + stop_distance_mm(latch_v, acc) : 0;
  double b = e.pre_move_distance_mm + e.max_seek_travel_mm + over + (mode_is_pushing(e.mode) ? e.push_distance_mm : 0) +
             2 * e.max_backoff_mm + index + e.pull_off_mm + std::abs(e.switch_compensation_mm) + final_d + stop + 1;
  const int partner = partner_index(r.settings, a);
  if (partner >= 0) {
    const int slave = master_index(r.settings, a) >= 0 ? static_cast<int>(a) : partner;
    const AxisSettings& sl = r.settings.axes[static_cast<std::size_t>(slave)];
    b += sl.max_misalignment_mm + std::abs(sl.pull_off_mm - r.settings.axes[static_cast<std::size_t>(master_index(r.settings, static_cast<std::size_t>(slave)))].pull_off_mm);
    // A commutator slave rides along with its master, then searches its own edge.
    if (slave == static_cast<int>(a) && sl.slave_mode == SlaveMode::external_commutator)
      b += e.pull_off_mm + sl.max_misalignment_mm + e.max_stop_distance_mm + 2 * e.max_backoff_mm + e.pull_off_mm + 1;
  }
  return b;
}

double time_bound(rig::Rig& r, const Machine& m, const CyclePlan& plan) {
  double t = 20;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(plan.movers & axis_bit(a))) continue;
    const AxisSettings e = effective(r.settings, a);
    const double v = mm_per_min_to_mm_per_s(mode_uses_switch(e.mode) ? e.latch_feedrate_mm_per_min : e.seek_feedrate_mm_per_min);
    if (v > 0) t += 2 * path_bound(r, m, a, r.actual(a)) / v;
  }
  return t;
}

void verdict(Watch& w, rig::Rig& r, const Machine& m, const Causes& causes, std::uint32_t cycles_before) {
  const CyclePlan& plan = w.plan;
  const Status& st = r.status();
  const std::uint32_t seen = w.alarms_seen;
  if (const std::uint32_t stray = seen & ~causes.allowed) {
    std::ostringstream o;
    o << "alarms seen: " << alarm_list(seen) << "; allowed by the causes: " << alarm_list(causes.allowed);
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (st.axes[a].alarm) o << "; " << describe_alarm(a, st.axes[a].alarm, r.settings) << " (phase " << phase_name(st.axes[a].alarm.phase) << ")";
    w.fail("alarm " + alarm_list(stray) + " without a cause", o.str());
  }
  if (!causes.must.empty() && seen == 0) w.fail(causes.must.front() + " raised no alarm");
  if (w.refused) {
    const std::uint32_t settings_codes = (1u << static_cast<unsigned>(AlarmCode::settings_fault)) |
                                         (1u << static_cast<unsigned>(AlarmCode::slave_sensor_missing));
    if (!(seen & settings_codes)) w.fail("a cycle the configuration check refuses ended without a settings alarm", alarm_list(seen));
    if (st.last_command_result != CommandResult::refused_settings_fault)
      w.fail("a cycle the configuration check refuses was not refused", std::string(command_result_name(st.last_command_result)));
  }
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const double bound = path_bound(r, m, a, w.window_start_x[a]);
    if (w.path[a] > bound) {
      std::ostringstream o;
      o << kAxisUpper[a] << " travelled " << w.path[a] << ", bound " << bound;
      w.fail("a cycle travelled beyond its bounded distance", o.str());
    }
  }
  if (seen != 0 || w.refused) return;
  if (st.homing_cycles != cycles_before + 1) w.fail("a cycle ended without an alarm but was not counted as completed");
  if (plan.all) w.assign_unsequenced();
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisMask bit = axis_bit(a);
    if (!((plan.covered | plan.unsequenced) & bit)) continue;
    const AxisSettings e = effective(r.settings, a);
    if (e.mode == HomingMode::disabled && master_index(r.settings, a) < 0) continue;
    if (!st.axes[a].homed) {
      w.fail("a cycle ended without an alarm and an axis of it not homed", std::string(1, kAxisUpper[a]));
      continue;
    }
    if (!(w.flipped & bit) && (plan.covered & bit))
      w.fail("an axis was homed without ever being unhomed by its cycle", std::string(1, kAxisUpper[a]));
    const Truth& t = w.truth[a];
    if (!t.valid) continue;
    const double x = r.actual(a);
    const bool final_move = (plan.covered & bit) && final_move_wanted(e);
    if (final_move) {
      if (std::abs(st.axes[a].position_mm - e.final_position_mm) > 1e-9) {
        std::ostringstream o;
        o << kAxisUpper[a] << " at " << st.axes[a].position_mm << ", final position " << e.final_position_mm;
        w.fail("the final move did not end at the final position", o.str());
      }
    } else if (t.has_rest && std::abs(x - t.rest) > t.tol) {
      std::ostringstream o;
      o << kAxisUpper[a] << " carriage " << x << ", rest point " << t.rest << " (tolerance " << t.tol << ")";
      w.fail("did not come to rest at pull-off from its reference edge", o.str());
    }
  }
}

}  // namespace campaign
