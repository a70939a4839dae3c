// A generated machine told as a story a reader can follow: one paragraph
// per axis, the sequence, and what was planned to go wrong.
#include <sstream>

#include "homing/motion.hpp"
#include "machine.hpp"

namespace campaign {
namespace {

const char* fault_name(sim::Fault f) {
  switch (f) {
    case sim::Fault::none: return "none";
    case sim::Fault::sensor_stuck_active: return "sensor stuck active";
    case sim::Fault::sensor_stuck_inactive: return "sensor stuck inactive";
    case sim::Fault::wire_break: return "wire break";
    case sim::Fault::drive_fault: return "drive fault";
    case sim::Fault::stall_dead: return "stall output dead";
    case sim::Fault::stall_stuck: return "stall output stuck on";
    case sim::Fault::drive_never_answers: return "drive never answers its home request";
    case sim::Fault::drive_answers_at_once: return "drive answers its home request at once";
    case sim::Fault::drive_done_lost: return "drive's home done lost";
    case sim::Fault::indexer_stuck_locked: return "indexer stuck locked";
    case sim::Fault::indexer_never_locks: return "indexer never locks";
    case sim::Fault::encoder_reversed: return "encoder counting the wrong way";
    case sim::Fault::limits_dead: return "limit switches dead";
    case sim::Fault::limits_stuck: return "limit switches stuck active";
  }
  return "?";
}

const char* pre_move_name(PreMove p) {
  switch (p) {
    case PreMove::none: return "none";
    case PreMove::if_sensor_active: return "if sensor active";
    case PreMove::always: return "always";
  }
  return "?";
}

std::string mask_letters(AxisMask m) {
  std::string out;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (m & axis_bit(a)) out += kAxisUpper[a];
  return out.empty() ? "-" : out;
}

void motion(std::ostringstream& o, const AxisSettings& s) {
  o << mode_name(s.mode) << " toward " << (s.direction == Direction::positive ? "+" : "-") << ", seek "
    << s.seek_feedrate_mm_per_min << " latch " << s.latch_feedrate_mm_per_min << " jog "
    << s.jog_feedrate_mm_per_min << " /min, accel " << s.acceleration_mm_per_s2 << ", max seek "
    << s.max_seek_travel_mm << " max stop " << s.max_stop_distance_mm << " (needs " << seek_stop_distance_mm(s)
    << ") max back-off " << s.max_backoff_mm << ", pre-move " << pre_move_name(s.pre_move_mode) << " "
    << s.pre_move_distance_mm << ", push " << s.push_distance_mm << ", index pitch " << s.index_pitch_mm
    << ", home " << s.home_position_mm << ", final " << (s.final_move_enable ? "on " : "off ")
    << s.final_position_mm << ", soft limits " << (s.soft_limits_enable ? "on [" : "off [") << s.soft_limit_min_mm
    << ", " << s.soft_limit_max_mm << "]";
}

void own(std::ostringstream& o, const AxisSettings& s) {
  o << "sensor " << (s.sensor_nc ? "NC" : "NO") << ", debounce " << s.debounce_ms << " ms, pull-off "
    << s.pull_off_mm << ", compensation " << s.switch_compensation_mm << ", max misalignment "
    << s.max_misalignment_mm << ", shared limit " << (s.shared_limit ? "yes" : "no");
}

void machine_side(std::ostringstream& o, const sim::AxisConfig& c, const AxisPlan& p) {
  o << "cam [" << c.sensor_min_mm << ", " << c.sensor_max_mm << "] (seek meets " << p.cam_edge_mm
    << ") hysteresis " << c.hysteresis_mm << " noise " << c.noise_mm << " bounce " << c.bounce_ms
    << " ms; carriage starts at " << c.actual_position_mm << " (" << p.start_gap_mm
    << (p.start_gap_mm < 0 ? " = on the sensor" : " from the edge") << "); stops [" << c.hard_stop_min_mm << ", "
    << c.hard_stop_max_mm << "]";
  if (c.index_pitch_mm > 0) o << "; index every " << c.index_pitch_mm << " from " << c.index_offset_mm;
  o << "; encoder offset " << c.absolute_offset_mm;
}

}  // namespace

std::string story(const Machine& m) {
  std::ostringstream o;
  const Settings& st = m.settings;
  o << "seed " << m.seed << ": control periods of about 1 ms, one in ten up to " << m.max_dt_s * 1000
    << " ms; alarm clears homed " << st.global.alarm_clears_homed << ", without homing "
    << static_cast<int>(st.global.allowed_without_homing) << ", permit required " << st.global.permit_required
    << ", failure policy " << name_of(st.global.failure_policy) << "\n  sequence:";
  for (std::size_t i = 0; i < 6; ++i) o << " " << (i + 1) << ":" << mask_letters(st.global.sequence_steps[i]);
  const CyclePlan plan = plan_cycle(st, true, 0);
  o << "; so home-all covers " << mask_letters(plan.covered) << ", assigns unsequenced " << mask_letters(plan.unsequenced)
    << ", moves " << mask_letters(plan.movers) << "\n";
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisSettings& s = st.axes[a];
    const AxisPlan& p = m.plan[a];
    o << "  " << kAxisUpper[a] << ": ";
    if (p.role == Role::master)
      o << "master of " << kAxisUpper[static_cast<std::size_t>(p.partner)]
        << (p.commutator ? " (external commutator)" : " (software-slaved)") << ", ";
    if (p.role == Role::slave) {
      o << "slave of " << kAxisUpper[static_cast<std::size_t>(p.partner)]
        << (p.commutator ? " through an external commutator" : " on its own output") << ", skew " << p.skew_mm
        << (p.bad_skew ? " (beyond the limit)" : "") << "; its inherited fields "
        << (p.differs ? "differ (to be ignored): " : "copy the master's: ");
    }
    motion(o, s);
    o << "; ";
    own(o, s);
    o << "\n     machine: ";
    machine_side(o, m.sim.axes[a], p);
    if (p.limits) {
      const sim::AxisConfig& c = m.sim.axes[a];
      o << "; limit switches at " << c.limit_min_mm << " and " << c.limit_max_mm << " (" << (s.limits_nc ? "NC" : "NO")
        << "), overtravel " << s.limit_overtravel_mm;
    }
    if (s.mode == HomingMode::home_cam)
      o << "; home cam edge " << (s.cam_edge == CamEdge::ahead ? "ahead" : "behind") << ", starts with "
        << cam_start_name(p.cam_start);
    if (p.reach_side) o << "; the " << (p.reach_side > 0 ? "positive" : "negative") << " limit switch within jogs and moves";
    if (p.cam_missing) o << "; CAM BEYOND THE LIMIT SWITCHES";
    if (p.cam_at_limit) o << "; LIMIT SWITCH WITHIN THE LATCH OR PULL-OFF";
    if (p.short_cam) o << "; CAM SHORTER THAN THE STOP";
    if (p.rest_on_sensor) o << "; SHARED LIMIT RESTS ON ITS SENSOR";
    if (p.indexer)
      o << "; locking indexer (unlock " << m.sim.axes[a].unlock_delay_ms << " ms, lock " << m.sim.axes[a].lock_delay_ms
        << " ms, timeout " << m.settings.axes[a].lock_timeout_ms << " ms)";
    if (p.start_fault != sim::Fault::none) o << "; FAULT FROM POWER-UP: " << fault_name(p.start_fault);
    if (p.following_error)
      o << "; stop told by following error above " << m.settings.axes[a].max_following_error_mm
        << " (encoder resolution " << m.sim.axes[a].encoder_resolution_mm << ", noise "
        << m.sim.axes[a].encoder_noise_mm << ")";
    if (p.encoder_invalid) o << "; ENCODER INVALID";
    // What the service acts (service_acts.cpp) find here: the far end a
    // measurement travels to, and how near a reference check must find its edge.
    if (p.far_stop_near) o << "; far stop pulled in within a measurement's reach";
    o << "; refcheck tolerance " << s.refcheck_tolerance_mm;
    o << "\n";
  }
  if (m.invalid != Invalid::none)
    o << "  INVALID SETTINGS on " << kAxisUpper[m.invalid_axis] << ": " << invalid_name(m.invalid) << "\n";
  if (auto f = first_fault(st)) o << "  the configuration check says: " << describe_fault(*f, st) << "\n";
  else o << "  the configuration check accepts these settings\n";
  o << "  power-up: " << m.powerup_periods << " periods" << (m.start_held_at_powerup ? " with the start button held" : "")
    << "; first cycle started by " << (m.start_by_button ? "the start button" : "the Modbus command")
    << ", estimated " << m.cycle_estimate_s << " s";
  for (const Event& e : m.events) o << "; " << event_name(e.kind) << " on " << kAxisUpper[e.axis] << " at " << e.at_s << " s";
  o << "\n";
  return o.str();
}

}  // namespace campaign
