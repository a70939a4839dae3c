// The acts of a run between cycles: jogs and moves, a hard-limit trip and
// its recovery, lost steps, and a jog that must not carry an invalid slave.
#include "../truth.hpp"
#include "homing/motion.hpp"
#include "run.hpp"

namespace campaign {

bool Run::move_pending(std::size_t a) const {
  const Phase p = r_.axis(a).phase;
  return p == Phase::move || p == Phase::unlock;
}

void Run::exercise_motion() {
  std::vector<std::size_t> cand;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisSettings e = effective(r_.settings, a);
    // Not one standing on its tripped shared-limit sensor: only a jog away is its to make.
    const int sl = slave_index(r_.settings, a);
    const bool on_limit = (r_.settings.axes[a].shared_limit && r_.axis(a).sensor) ||
                          (sl >= 0 && r_.settings.axes[static_cast<std::size_t>(sl)].shared_limit &&
                           r_.axis(static_cast<std::size_t>(sl)).sensor);
    // Nor one whose limit switches a fault holds active: it may not move at all.
    const bool limits_stuck = r_.sim().axis_config(a).fault == sim::Fault::limits_stuck;
    // Nor one standing on a limit switch (a move would be refused: only a jog away is its to make).
    if (master_index(r_.settings, a) < 0 && homed_axis(a) && e.soft_limits_enable && e.mode != HomingMode::disabled &&
        !on_limit && !limits_stuck && !on_limit_switch(a))
      cand.push_back(a);
  }
  if (cand.empty() || r_.status().alarm) return;
  const std::size_t a = pick(cand);
  const int slave = slave_index(r_.settings, a);
  const AxisMask movers = with_slave(a);
  const AxisSettings e = effective(r_.settings, a);
  Causes causes;
  if (e.shared_limit || (slave >= 0 && r_.settings.axes[static_cast<std::size_t>(slave)].shared_limit))
    causes.add("the jogged pair's shared-limit sensor", {AlarmCode::hard_limit}, movers);
  limit_sensor_faults(causes);
  // Soft limits past a limit switch: a jog or move may run into it.
  if (e.limits_fitted) causes.add(std::string(1, kAxisUpper[a]) + "'s limit switch within its jogs and moves", {AlarmCode::limit_switch}, movers);
  w_->clear_alarms_seen();
  w_->set_outside_movers(movers);
  const int dir = d_.chance(0.5) ? 1 : -1;
  say(std::string("jog ") + kAxisUpper[a] + (dir > 0 ? " +" : " -"));
  r_.jog(a, dir);
  const double jog_s = d_.u(0.05, 1.0);
  bool interrupted = false;
  if (const auto ev = motion_event(a)) {
    r_.run_for(d_.u(0.0, jog_s));
    apply_in_motion(*ev, causes);
    acts_ |= act::event_in_jog_or_move;
    interrupted = true;
  }
  r_.run_for(interrupted ? 0.05 : jog_s);
  r_.release_jogs();
  settle(10);
  if (interrupted) {
    w_->set_outside_movers(0);
    mark("jog interrupted", static_cast<std::uint8_t>(seen::present | (w_->alarms_seen ? seen::alarmed : 0)));
    if (auto u = explain(*w_, causes, r_.settings)) w_->fail(u->what + " during jogs and moves", u->detail);
    return;
  }
  bool stopped_short_any = false;
  if (!r_.status().alarm && homed_axis(a)) {
    const double target = r_.axis(a).position_mm + d_.u(-40, 40);
    const bool outside = target < e.soft_limit_min_mm || target > e.soft_limit_max_mm;
    say(std::string("move ") + kAxisUpper[a] + " to " + std::to_string(target));
    r_.move(a, target);
    const CommandResult res = r_.status().last_command_result;
    if (outside && res != CommandResult::refused_soft_limit) w_->fail("a move outside the soft limits was not refused", std::string(command_result_name(res)));
    if (!outside && res != CommandResult::accepted) w_->fail("a move inside the soft limits was refused", std::string(command_result_name(res)));
    bool stopped_short = false;
    if (!outside && res == CommandResult::accepted)
      if (const auto ev = motion_event(a)) {
        r_.run_until([&] { return r_.axis(a).velocity_mm_per_s != 0 || !ok(); }, 1);
        r_.run_for(d_.u(0.0, 0.2));
        apply_in_motion(*ev, causes);
        acts_ |= act::event_in_jog_or_move;
        stopped_short = stopped_short_any = true;
      }
    // (A locking indexer unlocks first: the move waits in phase unlock, seeds 5550935, 12018743.)
    r_.run_until([&] { return (!r_.any_moving() && !move_pending(a)) || !ok(); }, 120);
    settle(10);
    if (!outside && !stopped_short && !r_.status().alarm && ok() && std::abs(r_.axis(a).position_mm - target) > 1e-9)
      w_->fail("a move did not arrive", std::to_string(r_.axis(a).position_mm) + " for " + std::to_string(target));
    if (ok()) acts_ |= act::jog_and_move;
  }
  if (slave >= 0 && !stopped_short_any && d_.chance(0.3) && !r_.status().alarm) {
    r_.move(static_cast<std::size_t>(slave), r_.axis(static_cast<std::size_t>(slave)).position_mm + 1);
    if (r_.status().last_command_result != CommandResult::refused_slave_axis)
      w_->fail("a move commanded to a slave was not refused", std::string(command_result_name(r_.status().last_command_result)));
    settle(10);
  }
  w_->set_outside_movers(0);
  if (stopped_short_any) mark("move interrupted", static_cast<std::uint8_t>(seen::present | (w_->alarms_seen ? seen::alarmed : 0)));
  if (auto u = explain(*w_, causes, r_.settings)) w_->fail(u->what + " during jogs and moves", u->detail);
}

std::size_t Run::pick(const std::vector<std::size_t>& cand) {
  return cand[static_cast<std::size_t>(d_.integer(0, static_cast<int>(cand.size()) - 1))];
}

// The axis and the slave that moves with it.
AxisMask Run::with_slave(std::size_t a) const {
  const int slave = slave_index(r_.settings, a);
  return static_cast<AxisMask>(axis_bit(a) | (slave >= 0 ? axis_bit(static_cast<std::size_t>(slave)) : 0));
}

// A locking indexer's fault left by a cycle that ended without an alarm: the
// next unlock of its axis times out (stuck locked), or its next lock does
// (never locks, once the pin is out).
void Run::indexer_faults(Causes& causes) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const sim::Fault f = r_.sim().axis_config(a).fault;
    const std::string axis(1, kAxisUpper[a]);
    if (f == sim::Fault::indexer_stuck_locked)
      causes.add(axis + "'s indexer stuck locked", {AlarmCode::unlock_not_confirmed}, axis_bit(a));
    if (f == sim::Fault::indexer_never_locks)
      causes.add(axis + "'s indexer that never locks", {AlarmCode::lock_not_confirmed}, axis_bit(a));
  }
}

// A shared-limit sensor a fault holds active (stuck active, an open NC
// circuit) trips its homed axis as soon as no cycle runs (seed 8049361: it
// stuck during the last periods of a cycle that then ended homed).
void Run::limit_sensor_faults(Causes& causes) {
  indexer_faults(causes);
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const sim::Fault f = r_.sim().axis_config(a).fault;
    const bool held_active = f == sim::Fault::sensor_stuck_active || (f == sim::Fault::wire_break && r_.settings.axes[a].sensor_nc);
    if (f == sim::Fault::limits_stuck && r_.settings.axes[a].limits_fitted)
      causes.add(std::string(1, kAxisUpper[a]) + "'s limit switches stuck active", {AlarmCode::both_limits_active}, axis_bit(a));
    if (held_active && r_.settings.axes[a].shared_limit)
      causes.add(std::string(1, kAxisUpper[a]) + "'s shared-limit sensor held active by a fault", {AlarmCode::hard_limit}, axis_bit(a));
  }
}

// Before the first cycle, a short jog and a move of an unhomed axis, away
// from its sensor, as global.allowed_without_homing says (README): `all`
// lets both run at jog feedrate; `jog_reduced` only the jog, at 100 mm/min
// at most; `none` neither. A refused command moves nothing.
void Run::motion_before_homing() {
  const AllowedWithoutHoming allowed = r_.settings.global.allowed_without_homing;
  const double reduced_v = mm_per_min_to_mm_per_s(100.0);
  const auto jog_v_of = [&](const AxisSettings& e) {
    return allowed == AllowedWithoutHoming::all ? mm_per_min_to_mm_per_s(e.jog_feedrate_mm_per_min)
                                                : std::min(reduced_v, mm_per_min_to_mm_per_s(e.jog_feedrate_mm_per_min));
  };
  // About 1 mm of jog at full speed: the seek's travel allows 3 mm beyond where a cycle may start.
  const auto hold_s_of = [](double jog_v) { return std::min(0.3, 1.0 / jog_v); };
  // How far the jog and the move after it may carry the axis: a late control
  // period (up to max_dt_s) runs the jog on, accelerating, before the engine
  // sees the release, and the axis brakes from where it got to (seed 123942451:
  // a 16 ms period carried a fast jog 10 mm, past a limit switch 4.7 mm away).
  const auto reach_mm = [&](const AxisSettings& e) {
    const double v = jog_v_of(e);
    const double t = hold_s_of(v) + 2 * m_.max_dt_s;
    const double peak = std::min(v, e.acceleration_mm_per_s2 * t);
    return peak * t + stop_distance_mm(peak, e.acceleration_mm_per_s2) + 1.0;
  };
  const auto away_of = [](const AxisSettings& e) { return dir_of(e) > 0 ? -1 : 1; };
  std::vector<std::size_t> cand;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (master_index(r_.settings, a) >= 0 || r_.settings.axes[a].mode == HomingMode::disabled || r_.axis(a).homed ||
        r_.axis(a).sensor || r_.sim().axis_config(a).fault != sim::Fault::none)
      continue;
    // Not toward a limit switch it could reach: the act is a jog clear of the sensor, not a trip.
    const AxisSettings e = effective(r_.settings, a);
    const auto& c = r_.sim().axis_config(a);
    const double limit = away_of(e) > 0 ? c.limit_max_mm : c.limit_min_mm;
    if (e.limits_fitted && (limit - r_.actual(a)) * away_of(e) < reach_mm(e) + 0.5) continue;
    cand.push_back(a);
  }
  if (cand.empty() || r_.status().alarm) return;
  const std::size_t a = pick(cand);
  const AxisMask movers = with_slave(a);
  const AxisSettings e = effective(r_.settings, a);
  const int away = away_of(e);
  const double jog_v = jog_v_of(e);
  const double hold_s = hold_s_of(jog_v);
  w_->clear_alarms_seen();
  const bool jog_allowed = allowed != AllowedWithoutHoming::none;
  if (jog_allowed) w_->set_outside_movers(movers);
  say(std::string("jog unhomed ") + kAxisUpper[a] + (away > 0 ? " +" : " -") + " (allowed without homing: " +
      std::string(name_of(allowed)) + ")");
  const double x0 = r_.actual(a);
  r_.jog(a, away);
  step();
  const CommandResult jog_res = r_.status().last_command_result;
  // A locking indexer unlocks first: the jog's time starts once it may move.
  const double unlock_by = r_.sim().time_s() + 1.0;
  while (r_.axis(a).phase == Phase::unlock && r_.sim().time_s() < unlock_by && ok()) step();
  double fastest = 0;
  const double end = r_.sim().time_s() + hold_s;
  while (r_.sim().time_s() < end && ok()) {
    step();
    fastest = std::max(fastest, std::abs(r_.axis(a).velocity_mm_per_s));
  }
  r_.release_jogs();
  settle(10);
  if (jog_allowed && jog_res != CommandResult::accepted)
    w_->fail("a jog before homing that allowed_without_homing allows was refused", std::string(command_result_name(jog_res)));
  if (!jog_allowed && jog_res != CommandResult::refused_not_homed)
    w_->fail("a jog before homing with allowed_without_homing none was not refused as not homed",
             std::string(command_result_name(jog_res)));
  if (jog_allowed && std::abs(r_.actual(a) - x0) == 0 && ok()) w_->fail("a jog before homing that was accepted did not move");
  if (fastest > jog_v * (1 + 1e-9) + 1e-9)
    w_->fail("a jog before homing ran faster than allowed_without_homing lets it",
             std::to_string(fastest) + " mm/s, at most " + std::to_string(jog_v));
  w_->set_outside_movers(0);
  if (ok() && r_.status().alarm) w_->fail("an alarm during the jog before homing", alarm_list(w_->alarms_seen));
  if (!ok() || r_.status().alarm) return;
  // A move of 1 mm further away.
  const bool move_allowed = allowed == AllowedWithoutHoming::all;
  const double target = r_.axis(a).position_mm + away * 1.0;
  if (move_allowed) w_->set_outside_movers(movers);
  say(std::string("move unhomed ") + kAxisUpper[a] + " to " + std::to_string(target));
  r_.move(a, target);
  const CommandResult move_res = r_.status().last_command_result;
  r_.run_until([&] { return (!r_.any_moving() && !move_pending(a)) || !ok(); }, 30);
  settle(10);
  if (move_allowed && move_res != CommandResult::accepted)
    w_->fail("a move before homing with allowed_without_homing all was refused", std::string(command_result_name(move_res)));
  if (!move_allowed && move_res != CommandResult::refused_not_homed)
    w_->fail("a move before homing that allowed_without_homing forbids was not refused as not homed",
             std::string(command_result_name(move_res)));
  if (move_allowed && ok() && std::abs(r_.axis(a).position_mm - target) > 1e-9)
    w_->fail("a move before homing did not arrive", std::to_string(r_.axis(a).position_mm) + " for " + std::to_string(target));
  w_->set_outside_movers(0);
  if (w_->alarms_seen) w_->fail("an alarm during jogs and moves before homing", alarm_list(w_->alarms_seen));
  if (ok()) acts_ |= act::motion_before_homing;
  mark("jog and move before homing, allowed_without_homing " + std::string(name_of(allowed)), seen::present);
}

// Something happening while a jog or a move runs: an abort (stops it, no
// alarm), an e-stop, a drive fault on the moving axis or a communication loss.
std::optional<Event> Run::motion_event(std::size_t a) {
  if (!d_.chance(0.3)) return std::nullopt;
  Event e;
  e.kind = d_.pick({EventKind::abort, EventKind::estop, EventKind::drive_fault, EventKind::comm_lost});
  e.axis = a;
  return e;
}

// Settings written between cycles, as an HMI would, each valid by the
// documented rules: a lower seek feedrate (the axis stays homed: README
// "an axis is homed only in the frame it was homed in" keeps it for a
// feedrate), or the machine's origin moved (home position, soft limits and
// final position shifted together: the axis and its slave are unhomed before
// anything moves, and the next cycle homes them in the new coordinates).
void Run::change_settings() {
  if (r_.status().alarm || r_.any_moving()) return;
  std::vector<std::size_t> cand;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (master_index(r_.settings, a) < 0 && r_.settings.axes[a].mode != HomingMode::disabled) cand.push_back(a);
  if (cand.empty()) return;
  const std::size_t a = pick(cand);
  AxisSettings& s = r_.settings.axes[a];
  const int slave = slave_index(r_.settings, a);
  const bool was_homed = r_.axis(a).homed;
  if (mode_uses_switch(s.mode) && d_.chance(0.5)) {
    const double floor = s.latch_feedrate_mm_per_min * 1.5;
    if (s.seek_feedrate_mm_per_min * 0.5 <= floor) return;
    s.seek_feedrate_mm_per_min = d_.u(floor, s.seek_feedrate_mm_per_min);
    say(std::string("write ") + kAxisUpper[a] + ".seek_feedrate = " + std::to_string(s.seek_feedrate_mm_per_min));
    w_->settings_changed();
    for (int i = 0; i < 3; ++i) step();
    if (was_homed && !r_.axis(a).homed) w_->fail("a feedrate written between cycles unhomed its axis", std::string(1, kAxisUpper[a]));
    mark("settings written: seek feedrate", seen::present);
  } else {
    const double shift = d_.u(-5, 5);
    s.home_position_mm += shift;
    s.soft_limit_min_mm += shift;
    s.soft_limit_max_mm += shift;
    s.final_position_mm += shift;
    say(std::string("write ") + kAxisUpper[a] + ".home_position (and its soft limits, final position) shifted by " +
        std::to_string(shift));
    w_->settings_changed();
    step();
    const bool absolute = mode_is_absolute(s.mode);
    // Absolute axes take their coordinate from the encoder: the next cycle re-assigns them.
    if (was_homed && r_.axis(a).homed && !absolute)
      w_->fail("a home position written between cycles left its axis homed in the old coordinates", std::string(1, kAxisUpper[a]));
    if (slave >= 0 && r_.axis(static_cast<std::size_t>(slave)).homed && was_homed)
      w_->fail("a master's home position written between cycles left its slave homed", std::string(1, kAxisUpper[static_cast<std::size_t>(slave)]));
    for (int i = 0; i < 2; ++i) step();
    mark("settings written: origin moved", seen::present);
  }
  if (ok()) acts_ |= act::settings_changed;
}

// A shared-limit axis jogged into its own sensor: the trip must be recoverable.
void Run::hard_limit_recovery() {
  std::vector<std::size_t> cand;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisSettings e = effective(r_.settings, a);
    // A sensor the simulator has blinded (stuck inactive, an open NO circuit)
    // cannot trip: the jog would run into the stop with nothing to tell the engine.
    // And a cam long enough to hold the jog's stop: a limit switch a jog
    // overruns entirely (seed 8005639: 56,000 mm/min) releases again and
    // guards nothing, on any machine.
    const auto& c = r_.sim().axis_config(a);
    const double jog_v = mm_per_min_to_mm_per_s(e.jog_feedrate_mm_per_min);
    const bool holds = stop_distance_mm(jog_v, e.acceleration_mm_per_s2) + jog_v * m_.max_dt_s < c.sensor_max_mm - c.sensor_min_mm - c.hysteresis_mm;
    if (master_index(r_.settings, a) < 0 && homed_axis(a) && r_.settings.axes[a].shared_limit && !mode_is_pushing(e.mode) &&
        !r_.axis(a).sensor && c.fault == sim::Fault::none && holds)
      cand.push_back(a);
  }
  if (cand.empty() || r_.status().alarm) return;
  const std::size_t a = pick(cand);
  const AxisMask movers = with_slave(a);
  const int toward = dir_of(effective(r_.settings, a)) > 0 ? 1 : -1;
  w_->clear_alarms_seen();
  w_->set_outside_movers(movers);
  say(std::string("jog ") + kAxisUpper[a] + " toward its shared-limit sensor");
  r_.jog(a, toward);
  r_.run_until([&] { return r_.status().alarm || !ok(); }, 10);
  r_.release_jogs();
  settle(10);
  {
    Causes causes;
    limit_sensor_faults(causes);
    // The jogged axis, or its slave riding along, meets its sensor first.
    causes.add(std::string(1, kAxisUpper[a]) + "'s shared-limit sensor or its slave's", {AlarmCode::hard_limit}, movers);
    if (auto u = explain(*w_, causes, r_.settings)) w_->fail(u->what + " jogging into a shared-limit sensor", u->detail);
  }
  if (r_.axis(a).alarm.code != AlarmCode::hard_limit || !ok()) {
    w_->set_outside_movers(0);
    return;  // the soft limits kept it off its sensor
  }
  say("hard limit tripped; reset");
  w_->set_outside_movers(0);
  r_.reset_alarm();
  if (r_.status().last_command_result != CommandResult::accepted)
    w_->fail("after a hard-limit trip the reset was refused", std::string(command_result_name(r_.status().last_command_result)));
  for (int i = 0; i < 3; ++i) step();
  if (r_.status().alarm) {
    w_->fail("after a hard-limit trip the alarm latched again right after the reset");
    return;
  }
  // Toward the sensor: refused, nothing moves.
  w_->set_outside_movers(movers);
  const double x0 = r_.actual(a);
  say("jog toward the tripped sensor");
  r_.jog(a, toward);
  r_.run_for(0.3);
  r_.release_jogs();
  settle(10);
  if (std::abs(r_.actual(a) - x0) > 1e-9) w_->fail("a jog toward a tripped shared-limit sensor moved the axis");
  if (r_.status().alarm) {
    say("alarm again; reset");
    r_.reset_alarm();
    for (int i = 0; i < 3; ++i) step();
  }
  // Away from it: allowed until it releases.
  say("jog away from the tripped sensor");
  const double x1 = r_.actual(a);
  r_.jog(a, -toward);
  const bool released = r_.run_until([&] { return (!r_.sim().sensor_active(a) && !r_.axis(a).sensor) || r_.status().alarm || !ok(); }, 20);
  r_.release_jogs();
  settle(10);
  if (std::abs(r_.actual(a) - x1) <= 1e-9) w_->fail("a jog away from a tripped shared-limit sensor did not move the axis",
                                                   std::string(command_result_name(r_.status().last_command_result)));
  else if (!released || r_.status().alarm) w_->fail("a jog away from a tripped shared-limit sensor did not release it");
  else acts_ |= act::hard_limit_recovered;
  w_->set_outside_movers(0);
}

// Steps lost on plain switch axes, then a re-home: the correction shows them.
void Run::lost_steps() {
  std::vector<std::size_t> cand;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisSettings& s = r_.settings.axes[a];
    // Homed on its edge (not assigned unsequenced): the correction then measures the loss.
    if (m_.plan[a].role == Role::plain && mode_uses_switch(s.mode) && !mode_is_pushing(s.mode) && homed_axis(a) &&
        w_->truth[a].has_rest && !m_.plan[a].short_cam)
      cand.push_back(a);
  }
  if (cand.empty() || r_.status().alarm) return;
  const std::size_t a = pick(cand);
  const AxisSettings& s = r_.settings.axes[a];
  // Away from the cam: where the pull-off went (a home cam's: its cam_edge side).
  const double away = s.mode == HomingMode::home_cam && s.cam_edge == CamEdge::ahead ? dir_of(s) : -dir_of(s);
  // Never across the cam's edge: a carriage that jumps over it would show the
  // engine an edge where there is none (the simulator reports the jump as one).
  if (r_.sim().sensor_active(a)) return;
  const auto& c = r_.sim().axis_config(a);
  const double to_cam = away < 0 ? c.sensor_min_mm - r_.actual(a) : r_.actual(a) - c.sensor_max_mm;
  const double lost = d_.chance(0.5) ? away * d_.u(0, 3) : -away * d_.u(0, std::min(s.pull_off_mm, 0.8 * to_cam));
  // Nor onto it from the other side: a home cam's jogs may leave it beyond
  // its cam (seed 13004140).
  const double x1 = r_.actual(a) + lost, margin = c.hysteresis_mm + 0.1;
  if (s.mode == HomingMode::home_cam && std::min(r_.actual(a), x1) < c.sensor_max_mm + margin &&
      std::max(r_.actual(a), x1) > c.sensor_min_mm - margin)
    return;
  // Nor onto a limit switch: a carriage that jumps past one is no overrun of the engine's.
  if (s.limits_fitted && (r_.actual(a) + lost > c.limit_max_mm - 0.5 || r_.actual(a) + lost < c.limit_min_mm + 0.5)) return;
  say(std::string("lose ") + std::to_string(lost) + " on " + kAxisUpper[a]);
  r_.sim().lose_steps(a, lost);
  w_->carriage_jumped(a);
  if (r_.sim().at_hard_stop(a)) return;
  // A home-all measures the loss only where it homes the axis on its edge: an
  // unsequenced axis is assigned where it stands (correction 0); home it alone.
  const bool all = d_.chance(0.5) && (plan_cycle(r_.settings, true, 0).covered & axis_bit(a));
  if (!cycle(all, axis_bit(a), {}, false)) return;
  const double tol = 2 * rig::edge_tolerance_mm(s, 0.001) + 1e-9;
  if (r_.sim().axis_config(a).noise_mm == 0 && std::abs(r_.axis(a).home_correction_mm - lost) > tol)
    w_->fail("the home correction differs from the steps lost",
             std::to_string(r_.axis(a).home_correction_mm) + " for " + std::to_string(lost));
  else if (r_.sim().axis_config(a).noise_mm == 0)
    acts_ |= act::lost_steps_corrected;
}

// Refused settings with a slave that cannot be one: a jog of the axis it
// names must not carry it along either.
void Run::jog_invalid_slave() {
  const Invalid v = m_.invalid;
  if (v != Invalid::slave_of_disabled && v != Invalid::slave_of_slave && v != Invalid::two_slaves &&
      v != Invalid::master_not_on_switch && v != Invalid::slave_disabled && v != Invalid::slave_without_sensor)
    return;
  const std::size_t a = m_.invalid_axis;
  const int named = static_cast<int>(r_.settings.axes[a].slave_of) - 1;
  if (named < 0 || named >= static_cast<int>(kAxisCount) || named == static_cast<int>(a) || r_.status().estop) return;
  const std::size_t mi = static_cast<std::size_t>(named);
  AxisMask movers = axis_bit(mi);
  for (std::size_t s = 0; s < kAxisCount; ++s)
    if (static_cast<int>(r_.settings.axes[s].slave_of) - 1 == named) movers |= axis_bit(s);
  const double x = r_.actual(a);
  r_.reset_alarm();
  w_->set_outside_movers(movers);
  say(std::string("jog ") + kAxisUpper[mi] + ", which " + kAxisUpper[a] + " names as its master");
  r_.jog(mi, dir_of(r_.settings.axes[mi]) > 0 ? -1 : 1);
  const double end = r_.sim().time_s() + 0.2;
  while (r_.sim().time_s() < end && ok()) {
    step();
    if (std::abs(r_.actual(a) - x) > 1e-9)
      w_->fail(std::string("a slave the configuration check refuses (") + invalid_name(v) + ") followed its master's jog");
  }
  r_.release_jogs();
  settle(10);
  w_->set_outside_movers(0);
}

}  // namespace campaign
