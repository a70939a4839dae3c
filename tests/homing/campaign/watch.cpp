#include "watch.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "../truth.hpp"

namespace campaign {
namespace {

std::string fmt_axis(std::size_t a, rig::Rig& r, double x) {
  const AxisStatus& s = r.status().axes[a];
  std::ostringstream o;
  o << kAxisUpper[a] << " in phase " << phase_name(s.phase) << ", carriage " << x << ", position " << s.position_mm
    << ", velocity " << s.velocity_mm_per_s << ", alarm " << alarm_name(s.alarm.code) << ", at t " << r.sim().time_s();
  return o.str();
}

}  // namespace

Watch::Watch(rig::Rig& r, const Machine& m) : r_(r), m_(m) {
  for (std::size_t a = 0; a < kAxisCount; ++a) eff_[a] = effective(r_.settings, a);
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    x_prev_[a] = r_.actual(a);
    traced_[a] = Phase::idle;
  }
  for (std::size_t s = 0; s < kAxisCount; ++s)
    if (m_.plan[s].role == Role::slave) rel_ref_[s] = r_.actual(s) - r_.actual(static_cast<std::size_t>(m_.plan[s].partner));
  ran_dt_prev_ = r_.ran_dt_s;
  if (const char* t = std::getenv("HOMING_CAMPAIGN_TRACE")) trace_axes = *t ? 1 : 0;
}

void Watch::fail(const std::string& what, const std::string& detail) {
  if (failure_.what.empty()) failure_ = Failure{what, detail};
}

void Watch::clear_alarms_seen() {
  alarms_seen = global_alarms = 0;
  axis_alarms.fill(0);
  first_alarm.fill(Alarm{});
}

double Watch::accel_limit(std::size_t a) const { return eff_[a].acceleration_mm_per_s2; }

void Watch::begin_window(const CyclePlan& p, bool is_refused) {
  in_window = true;
  plan = p;
  // An unsequenced axis homed when the cycle starts keeps its coordinate
  // (docs/homing-methods.md "Sequence"): only one whose coordinate is its absolute encoder's is
  // read again. A gantry pair is kept or assigned together.
  AxisMask kept = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((p.unsequenced & axis_bit(a)) && r_.status().axes[a].homed && !mode_is_absolute(effective(r_.settings, a).mode))
      kept |= axis_bit(a);
  for (std::size_t s = 0; s < kAxisCount; ++s) {
    if (m_.plan[s].role != Role::slave) continue;
    const std::size_t m = static_cast<std::size_t>(m_.plan[s].partner);
    if (((kept >> s) & 1u) != ((kept >> m) & 1u)) kept &= static_cast<AxisMask>(~(axis_bit(s) | axis_bit(m)));
  }
  plan.unsequenced &= static_cast<AxisMask>(~kept);
  refused = is_refused;
  measured = 0;
  extra_path.fill(0);
  // Assigned again by this cycle: inside its soft limits from now. Not an
  // unsequenced axis that keeps its coordinate (seed 190056107 of the release
  // run: left beyond them by a measurement, it stays there through home-all).
  outside_soft_limits &= static_cast<AxisMask>(~(plan.covered | plan.unsequenced));
  flipped = 0;
  tampered = 0;
  path.fill(0);
  window_start_s = r_.sim().time_s();
  steps_off_.fill(false);
  for (std::size_t a = 0; a < kAxisCount; ++a)
    started_on_limit_[a] = effective(r_.settings, a).limits_fitted &&
                           (r_.sim().limit_active(a, false) || r_.sim().limit_active(a, true));
  back_.fill(false);
  stop_touched_.fill(false);
  limits_dead_seen_.fill(false);
  went_back_.fill(false);
  for (std::size_t a = 0; a < kAxisCount; ++a) started_at_stop_[a] = r_.sim().at_hard_stop(a);
  after.fill(After::brake);
  wind_down = FailurePolicy::stop_all;
  finishers = returners = 0;
  later_failure = false;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    window_start_x[a] = r_.actual(a);
    has_release_[a] = has_trigger_[a] = false;
    // The cycle assigns these again: the old truth no longer holds.
    if (!refused && ((plan.covered | plan.unsequenced) & axis_bit(a))) truth[a].valid = false;
  }
  for (std::size_t s = 0; s < kAxisCount; ++s) {
    if (m_.plan[s].role != Role::slave) continue;
    rel_ref_[s] = r_.actual(s) - r_.actual(static_cast<std::size_t>(m_.plan[s].partner));
    if (!square_[s]) square_[s] = carriage_rel(s);
    rack0_[s] = carriage_rel(s) - *square_[s];
    rack0_uncertain_[s] = square_uncertain_[s];
    pair_unhomed_seen_[s] = false;
    pair_under_way_[s] = false;
  }
  late_allowance_.fill(0);
  slipped_.fill(false);
  reversed = reversal_expected = reversal_known = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(plan.movers & axis_bit(a)) || effective(r_.settings, a).mode != HomingMode::home_cam ||
        r_.sim().axis_config(a).fault != sim::Fault::none)
      continue;
    reversal_known |= axis_bit(a);
    if (cam_lies_behind(r_, effective(r_.settings, a), a)) reversal_expected |= axis_bit(a);
  }
}

bool cam_lies_behind(rig::Rig& r, const AxisSettings& e, std::size_t a) {
  const auto& c = r.sim().axis_config(a);
  if (r.sim().sensor_active(a)) return false;
  const double dir = dir_of(e);
  const double x = r.sim().actual_position_mm(a);
  const double near = dir > 0 ? c.sensor_min_mm : c.sensor_max_mm;
  const double limit = dir > 0 ? c.limit_max_mm : c.limit_min_mm;
  const bool cam = c.sensor_max_mm >= c.sensor_min_mm;
  // A sensor reading inactive within the cam stands within its noise of an
  // edge, and switches on where the noise drew it, on the cam's side of the
  // carriage: just inside the near edge the cam still lies ahead (seed
  // 4420842 on camp-cam before the merge: 1.6 um inside, noise 5.5 um).
  const double middle = 0.5 * (c.sensor_min_mm + c.sensor_max_mm);
  return !(cam && (middle - x) * dir > 0 && (limit - near) * dir > 0);
}

double rest_from_edge(const AxisSettings& e, double ref, double compensation_mm) {
  if (e.mode == HomingMode::home_cam) {
    const double side = e.cam_edge == CamEdge::ahead ? dir_of(e) : -dir_of(e);
    return ref + side * e.pull_off_mm;
  }
  return rig::rest_point_mm(e, ref, compensation_mm);
}

void Watch::end_window() {
  in_window = false;
  for (std::size_t s = 0; s < kAxisCount; ++s)
    if (m_.plan[s].role == Role::slave) rel_ref_[s] = r_.actual(s) - r_.actual(static_cast<std::size_t>(m_.plan[s].partner));
}

void Watch::set_outside_movers(AxisMask mask) { outside_ = mask; }

void Watch::carriages_placed() {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (std::abs(r_.actual(a) - x_prev_[a]) > 0) truth[a].valid = false;
    x_prev_[a] = r_.actual(a);
    alarm_x0_[a] = rest_x_[a] = r_.actual(a);
  }
  for (std::size_t s = 0; s < kAxisCount; ++s)
    if (m_.plan[s].role == Role::slave) rel_ref_[s] = r_.actual(s) - r_.actual(static_cast<std::size_t>(m_.plan[s].partner));
}

double Watch::carriage_rel(std::size_t slave) const {
  return r_.actual(slave) - r_.actual(static_cast<std::size_t>(m_.plan[slave].partner));
}

std::optional<double> Watch::pair_rack(std::size_t slave) const {
  if (square_uncertain_[slave]) return std::nullopt;
  return square_[slave] ? carriage_rel(slave) - *square_[slave] : 0.0;
}

void Watch::pair_unhomed(AxisMask axes) {
  for (std::size_t s = 0; s < kAxisCount; ++s)
    if (m_.plan[s].role == Role::slave &&
        (axes & (axis_bit(s) | axis_bit(static_cast<std::size_t>(m_.plan[s].partner))))) {
      square_[s].reset();
      square_uncertain_[s] = false;
    }
}

// A side's carriage went where its steps did not take it: the module's square
// (counted in steps) and the carriages' part by as much, until it squares again.
void Watch::square_unsure(std::size_t a) {
  for (std::size_t s = 0; s < kAxisCount; ++s)
    if (m_.plan[s].role == Role::slave && (s == a || static_cast<std::size_t>(m_.plan[s].partner) == a))
      square_uncertain_[s] = true;
}

void Watch::restarted(AxisMask homed) {
  pair_unhomed(kAllAxes);
  for (std::size_t s = 0; s < kAxisCount; ++s) {
    if (m_.plan[s].role != Role::slave) continue;
    const AxisMask pair = static_cast<AxisMask>(axis_bit(s) | axis_bit(static_cast<std::size_t>(m_.plan[s].partner)));
    if ((homed & pair) != pair) square_unsure(s);
  }
}

void Watch::settings_changed() {
  for (std::size_t a = 0; a < kAxisCount; ++a) eff_[a] = effective(r_.settings, a);
}

void Watch::pair_slipped(std::size_t a) {
  square_unsure(a);
  for (std::size_t s = 0; s < kAxisCount; ++s)
    if (m_.plan[s].role == Role::slave && (s == a || static_cast<std::size_t>(m_.plan[s].partner) == a)) slipped_[s] = true;
}

void Watch::carriage_jumped(std::size_t a) {
  square_unsure(a);
  truth[a].valid = false;
  x_prev_[a] = r_.actual(a);
}

void Watch::period() {
  const double engine_dt = ran_dt_prev_;  // the engine integrated the period before this one
  ran_dt_prev_ = r_.ran_dt_s;
  const Status& st = r_.status();
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const Alarm& al = st.axes[a].alarm;
    if (!al) continue;
    alarms_seen |= alarm_bit(al.code);
    if (!axis_alarms[a]) first_alarm[a] = al;
    axis_alarms[a] |= alarm_bit(al.code);
  }
  if (st.global_alarm != AlarmCode::none) {
    alarms_seen |= alarm_bit(st.global_alarm);
    global_alarms |= alarm_bit(st.global_alarm);
  }
  if (st.alarm && !alarm_prev_) {
    alarm_periods_ = 0;
    for (std::size_t a = 0; a < kAxisCount; ++a) brake_from_now(a, st);
  }
  if (st.alarm) ++alarm_periods_;
  policy_period(st);
  if (powering_up && (st.homing || st.command_count != 0)) {
    fail("a start button held at power-up started home-all");
    powerup_started = true;
  }
  if (in_window && refused && st.homing) {
    fail("a cycle the configuration check refuses started");
    refused = false;  // it runs: hold it to the rules of a running cycle from here
  }
  for (std::size_t a = 0; a < kAxisCount; ++a) axis_period(a, engine_dt);
  if (!powerup_started) racking(engine_dt);
  alarm_prev_ = st.alarm;
}

void Watch::axis_period(std::size_t a, double engine_dt) {
  const Status& st = r_.status();
  const AxisStatus& as = st.axes[a];
  const AxisSettings& e = eff_[a];
  const double x = r_.actual(a);
  const double x_eng = x_prev_[a];  // the carriage when the engine's status was taken (before this period ran)
  const double v = as.velocity_mm_per_s;
  const double step = std::abs(x - x_prev_[a]);
  const bool moved = step > 1e-12;
  const AxisMask bit = axis_bit(a);
  const bool drive_faulted = r_.sim().axis_config(a).fault == sim::Fault::drive_fault;
  const int master = master_index(r_.settings, a);
  if (in_window) path[a] += step;

  if (trace_axes && as.phase != traced_[a]) {
    traced_[a] = as.phase;
    std::printf("t %.4f %s\n", r_.sim().time_s(), fmt_axis(a, r_, x).c_str());
  }

  // The flip to homed, with the edges as they stood before this period.
  // A switch mode must have been unhomed by its cycle first; the others are
  // assigned (again) when their step begins.
  if (in_window && (plan.covered & bit) && as.homed && !(flipped & bit) && e.mode != HomingMode::disabled &&
      ((!searches(e.mode) && e.mode != HomingMode::drive) || !homed_prev_[a]))
    on_flip(a, x_eng);
  if (!as.homed) truth[a].valid = false;
  homed_prev_[a] = as.homed;
  if (in_window && (plan.covered & bit) && !(flipped & bit)) track_edges(a);

  // Mechanical stops: touched only at reduced current (the push output on
  // for the period that brought it there: a push, or a push cut short by an
  // alarm braking on into the stop), or by a pushing axis whose dead sensor
  // let the seek run into the stop just behind it. A commutator slave rides
  // along with its master's output, into its stop too. Once at the stop it
  // may rest there, but never drives on into it at full current.
  // Limit switches that never trip cannot keep a carriage off its stop: a
  // home cam's search behind which the cam lies runs into it, losing steps
  // until max_seek_travel (docs/limit-switches.md, fault limits_dead).
  if (in_window && r_.sim().at_hard_stop(a)) stop_touched_[a] = true;
  // A fault injected in the window replaces limits_dead in the simulator
  // (one fault per axis): a search the dead switches let past them is still
  // on its way into the stop when they read again (seed 190010418 of the
  // release run: a home cam's stuck sensor injected 1 ms before the stop).
  if (m_.plan[a].limits && r_.sim().axis_config(a).fault == sim::Fault::limits_dead) limits_dead_seen_[a] = true;
  const bool limits_dead = limits_dead_seen_[a];
  if (r_.sim().at_hard_stop(a) && limits_dead) {
    pushed_to_stop_[a] = false;
  } else if (r_.sim().at_hard_stop(a)) {
    const bool pushing = pushes_into_stop(e.mode);
    const bool reduced = r_.engine.outputs().axes[a].push_output ||
                         (master >= 0 && r_.engine.outputs().axes[static_cast<std::size_t>(master)].push_output);
    const bool rides = master >= 0 && r_.settings.axes[a].slave_mode == SlaveMode::external_commutator &&
                       (dead_sensor & axis_bit(static_cast<std::size_t>(master)));
    const bool excused = (dead_sensor & bit) || rides;
    if (pushing && (reduced || excused)) pushed_to_stop_[a] = true;
    // Sent back by the failure policy to where the cycle found it, at its stop.
    const bool back_to_start = st.alarm && after[a] == After::go_back && started_at_stop_[a] &&
                               std::abs(x - window_start_x[a]) <= 1e-6;
    if (back_to_start) pushed_to_stop_[a] = true;
    // A pre-move "always" that starts nearer its far stop than its own length
    // meets it: the axis is not homed, so nothing tells the engine where that
    // stop is. A measurement ends pull-off and one pre-move from it, and a
    // cycle stopped by an alarm after its pre-move leaves the carriage one
    // pre-move nearer still (seed 193011366: 1.6 mm left, a pre-move of
    // 4 mm). Started that near, the touch is the placement's.
    // It stays excused while it rests or brakes there (an alarm of another
    // axis may turn the phase to return_to_start as it brakes).
    const auto& stops = r_.sim().axis_config(a);
    if (in_window && as.phase == Phase::pre_move &&
        pre_move_meets_far_stop(e, window_start_x[a], stops.hard_stop_min_mm, stops.hard_stop_max_mm))
      pre_move_met_stop_[a] = true;
    if (!(pushing && pushed_to_stop_[a]) && !back_to_start && !pre_move_met_stop_[a])
      fail(std::string("a carriage ran into a mechanical stop") +
               (m_.plan[a].differs ? " (a slave whose own inherited fields differ)" : ""),
           fmt_axis(a, r_, x));
    else if (!reduced && !excused && !back_to_start && v * dir_of(e) > 0)
      fail("a carriage drove into its mechanical stop at full current (push output off)", fmt_axis(a, r_, x));
  } else {
    pushed_to_stop_[a] = false;
    pre_move_met_stop_[a] = false;
  }

  // A locking indexer holds its axis: the motor never runs while the pin is
  // in (docs/homing-methods.md "Locking indexer"), except braking after the pin went in
  // on its own under an axis unlocked for motion (lock_engaged).
  if (r_.sim().moved_while_locked(a) && !(lock_struck & bit))
    fail("the motor ran while its locking indexer was locked", fmt_axis(a, r_, x));

  // Motion only where the configuration and the script allow it.
  const AxisMask allowed = (in_window && !refused ? plan.movers : AxisMask{0}) | outside_ | (powerup_started ? kAllAxes : 0);
  if (allowed & bit) grace_[a] = true;
  if (moved && !(allowed & bit) && !grace_[a]) {
    if (refused && in_window) fail("motion although the configuration check refused the cycle", fmt_axis(a, r_, x));
    else if (e.mode == HomingMode::disabled) fail("a disabled axis moved", fmt_axis(a, r_, x));
    else if (in_window && (plan.unsequenced & bit)) fail("an unsequenced axis moved", fmt_axis(a, r_, x));
    else if (in_window && (plan.covered & bit)) fail("an axis whose mode does not move moved", fmt_axis(a, r_, x));
    else if (in_window) fail("an axis outside the cycle moved", fmt_axis(a, r_, x));
    else fail("an axis moved that nothing commanded", fmt_axis(a, r_, x));
  }
  if (in_window && (plan.movers & bit) && moved && !st.alarm) {
    if (st.homing && st.sequence_step != plan.step[a])
      fail("an axis moved outside its sequence step",
           fmt_axis(a, r_, x) + "; its step " + std::to_string(plan.step[a]) + ", running " + std::to_string(st.sequence_step));
    const bool drive_homes = e.mode == HomingMode::drive && as.phase == Phase::drive_homing;
    if (!searches(e.mode) && as.phase != Phase::final_move && as.phase != Phase::stopping && !drive_homes)
      fail("a manual, absolute or drive-homed axis moved outside its final move (or its drive's homing)",
           fmt_axis(a, r_, x));
  }
  if (!(allowed & bit) && v == 0 && !r_.sim().moving(a)) grace_[a] = false;

  // Acceleration: no velocity change beyond what the axis (the pair) can do.
  const double acc = accel_limit(a);
  if (!drive_faulted && acc > 0 && engine_dt > 0) {
    const double dv = std::abs(v - v_prev_[a]);
    if (dv > acc * engine_dt * (1 + 1e-9) + 1e-6) {
      std::ostringstream o;
      o << fmt_axis(a, r_, x) << "; velocity " << v_prev_[a] << " -> " << v << " in " << engine_dt * 1000
        << " ms, at most " << acc * engine_dt << " at " << acc << "/s2";
      // The class names the phase that commanded it (the one before this
      // status), and whether it was a dead stop or the higher acceleration
      // of a gantry's two: they are different bugs.
      const double own = r_.settings.axes[a].acceleration_mm_per_s2;
      const int partner = partner_index(r_.settings, a);
      std::string how = v == 0 ? "a dead stop" : "a velocity change";
      if (partner >= 0 && dv <= own * engine_dt * (1 + 1e-9) + 1e-6) how = "a gantry side at its own, not the pair's lower, acceleration";
      else if (partner >= 0 && dv <= r_.settings.axes[static_cast<std::size_t>(partner)].acceleration_mm_per_s2 * engine_dt * (1 + 1e-9) + 1e-6)
        how = "a gantry side at its partner's acceleration, beyond its own";
      fail(std::string("velocity changed faster than the acceleration: ") + how + " in phase " +
               std::string(phase_name(phase_prev_[a])),
           o.str());
    }
  }

  // While an alarm is latched: only the braking of what it stopped, and
  // what the failure policy lets go on (policy_watch.cpp).
  if (st.alarm && !drive_faulted) after_alarm(a, x, v, moved);
  if (in_window) {
    const Phase p = as.phase;
    if (p == Phase::push || p == Phase::push_to_stop || p == Phase::drive_homing) steps_off_[a] = true;
  }

  // A homed axis: its coordinate is the truth's, and its carriage stays inside enforced soft limits.
  if (truth[a].valid && as.homed) {
    const double pos_eng = x_eng + truth[a].offset;
    if (std::abs(as.position_mm - pos_eng) > truth[a].tol + 1e-6) {
      std::ostringstream o;
      o << fmt_axis(a, r_, x) << "; the truth is " << pos_eng;
      fail("a homed axis's coordinate drifted from the truth", o.str());
      truth[a].valid = false;
    }
    const double pos = x + truth[a].offset;
    const double tol = truth[a].tol + 1e-6;
    const bool outside = pos < e.soft_limit_min_mm - tol || pos > e.soft_limit_max_mm + tol;
    if (!outside) outside_soft_limits &= static_cast<AxisMask>(~bit);
    if (e.soft_limits_enable && !in_window && outside && !(outside_soft_limits & bit)) {
      std::ostringstream o;
      o << fmt_axis(a, r_, x) << "; machine position (truth) " << pos << " outside [" << e.soft_limit_min_mm << ", "
        << e.soft_limit_max_mm << "]";
      fail("a homed carriage passed an enforced soft limit", o.str());
    }
  }

  const double ran_dt = r_.ran_dt_s > 0 ? r_.ran_dt_s : 1e-3;
  limit_overrun(a, x, std::max({std::abs(v_prev_[a]), std::abs(v), step / ran_dt}));
  cam_reversal(a);

  x_prev_[a] = x;
  v_prev_[a] = v;
  phase_prev_[a] = as.phase;
}

// No carriage passes a limit switch by more than its stopping distance: the
// stop at the axis's acceleration from the speed it had at the end of the
// period the switch tripped in, one late control period of travel and the
// simulator's tolerance.
// The switches are where the simulated machine has them (not what the engine
// believes); a switch a fault keeps from ever tripping is not held to it.
void Watch::limit_overrun(std::size_t a, double x, double speed) {
  // Nor one that read dead earlier in this window and trips again only
  // because a fault injected since took limits_dead's place (seed 190010418).
  if (!m_.plan[a].limits || r_.sim().axis_config(a).fault == sim::Fault::limits_dead || limits_dead_seen_[a]) {
    past_limit_[a] = false;
    return;
  }
  const sim::AxisConfig& c = m_.sim.axes[a];
  const double beyond = std::max(c.limit_min_mm - x, x - c.limit_max_mm);
  if (beyond < 0) {
    past_limit_[a] = false;
    return;
  }
  // The speed at the end of the period it tripped in is what the engine
  // brakes from: the status of the next period reports it (a carriage still
  // accelerating ends that period faster than it crossed: seed 2719).
  if (!past_limit_[a]) {
    trip_speed_[a] = speed;
    trip_fresh_[a] = true;
  } else if (trip_fresh_[a]) {
    trip_speed_[a] = std::max(trip_speed_[a], std::abs(r_.status().axes[a].velocity_mm_per_s));
    trip_fresh_[a] = false;
  }
  past_limit_[a] = true;
  const double v0 = trip_speed_[a];
  const double allowed = stop_distance_mm(v0, accel_limit(a)) + v0 * m_.max_dt_s + kLimitTolerance_mm;
  if (beyond > allowed) {
    std::ostringstream o;
    o << fmt_axis(a, r_, x) << "; " << beyond << " past the limit switch at "
      << (x < c.limit_min_mm ? c.limit_min_mm : c.limit_max_mm) << ", tripped at " << v0 << " mm/s, allowed "
      << allowed;
    fail("a carriage passed a limit switch by more than its stopping distance", o.str());
  }
}

// A home cam's search reverses exactly when it meets the limit switch ahead
// (docs/limit-switches.md): it enters limit_reversal only in a period whose
// inputs show that switch active, and never seeks on in cam_seek past a
// period that showed it (a cam trigger in the same period takes precedence;
// both switches at once are both_limits_active). A phase entered during a
// period runs in it (the first phase of a sequence step runs from the next
// period: campaign seed 604), so a period that began and ended in cam_seek
// shows what the search decided on the inputs it read.
void Watch::cam_reversal(std::size_t a) {
  const AxisSettings& e = eff_[a];
  const bool read_min = limit_min_read_[a], read_max = limit_max_read_[a];
  limit_min_read_[a] = r_.sim().limit_active(a, false);
  limit_max_read_[a] = r_.sim().limit_active(a, true);
  if (e.mode != HomingMode::home_cam || !e.limits_fitted || !in_window || !(plan.covered & axis_bit(a))) return;
  const AxisStatus& as = r_.status().axes[a];
  const bool ahead = dir_of(e) > 0 ? read_max : read_min;
  const bool both = read_min && read_max;
  // Under a locking indexer's unlock the status shows unlock while the
  // search runs beneath it: the reversal may have been decided in any period
  // of the hold (campaign seed 184458299: on the switch when the unlock
  // began, moved off it by lost steps before the pin came out).
  if (as.phase == Phase::unlock) ahead_while_held_[a] = (phase_prev_[a] == Phase::unlock && ahead_while_held_[a]) || ahead;
  const bool decided_held = phase_prev_[a] == Phase::unlock && ahead_while_held_[a];
  if (as.phase == Phase::limit_reversal && phase_prev_[a] != Phase::limit_reversal) {
    reversed |= axis_bit(a);
    if (!ahead && !decided_held) fail("the home cam search reversed without meeting the limit switch ahead", fmt_axis(a, r_, r_.actual(a)));
  }
  if (as.phase == Phase::cam_seek && phase_prev_[a] == Phase::cam_seek && ahead && !both && !r_.status().alarm)
    fail("the home cam search met the limit switch ahead and sought on", fmt_axis(a, r_, r_.actual(a)));
}

void Watch::racking(double engine_dt) {
  // The guard looks two of the engine's periods ahead: a period that ran
  // longer may carry the pair on by both sides' travel in the extra time.
  const double late_s = std::max(0.0, r_.ran_dt_s - 2 * engine_dt);
  for (std::size_t s = 0; s < kAxisCount; ++s) {
    if (m_.plan[s].role != Role::slave) continue;
    const std::size_t mi = static_cast<std::size_t>(m_.plan[s].partner);
    // A software-slaved pair turns at each edge together (docs/homing-methods.md
    // "Gantries: topologies"): a side that starts a back-off, a re-approach or
    // a pull-off finds the other starting it in the same period.
    if (!m_.plan[s].commutator) {
      const Phase ps = r_.status().axes[s].phase, pm = r_.status().axes[mi].phase;
      const auto turns = [](Phase p) { return p == Phase::back_off || p == Phase::reapproach || p == Phase::pull_off; };
      const bool alone = (pair_phase_prev_[s] != ps && turns(ps) && pm != ps) ||
                         (pair_phase_prev_[mi] != pm && turns(pm) && ps != pm);
      // A side whose sensor a fault forced meets a false edge the moment it
      // turns, and is back waiting within that period: the other side then
      // turns a period later, alone to look at (seed 244790: a slave sensor
      // stuck active between the pair's release and re-approach; 248571: a
      // wire broken on an NO slave sensor as the pair stopped on it, the
      // back-off "released" at once).
      const bool false_edge = (tampered & (axis_bit(s) | axis_bit(mi))) != 0;
      if (alone && !r_.status().alarm && !false_edge)
        fail("a software-slaved gantry side turned at its edge without the other",
             fmt_axis(s, r_, r_.actual(s)) + "; " + fmt_axis(mi, r_, r_.actual(mi)));
      pair_phase_prev_[s] = ps;
      pair_phase_prev_[mi] = pm;
    }
    // Each side as fast as it was at the period's start or as its command
    // takes it within the period: a side starting from rest accelerates on
    // for the whole late period (seed 194066258: a commutator slave entering
    // back_off at rest, 4.2 mm/s within 3.5 ms, in a period of 18 ms after
    // one of 0.9 ms; its command runs on its master's output channel).
    const auto fastest = [&](std::size_t x) {
      const AxisOutputs& o = r_.engine.outputs().axes[x];
      return std::max({std::abs(r_.status().axes[x].velocity_mm_per_s), std::abs(o.motor.velocity_mm_per_s),
                       std::abs(o.motion.target_velocity_mm_per_s)});
    };
    if (in_window) late_allowance_[s] += late_s * (fastest(s) + fastest(mi));
    const double rel = r_.actual(s) - r_.actual(mi);
    const double signed_dev = rel - rel_ref_[s];
    double dev = std::abs(signed_dev);
    // The promise as written (docs/homing-methods.md "Gantries: racking"):
    // never beyond max_misalignment from square, late periods included; 1 µm
    // for the arithmetic. Counted on the carriages from where the window
    // found them (lost steps before it cancel out), in a band the rack the
    // window found (on the step outputs, from where the pair was last square)
    // shifts: a racked pair may come back to square and the limit beyond.
    // Locked outside a cycle the pair stays locked, unless a side's drive
    // faulted while it moved: the other side brakes on, within the limit the
    // rule set sizes for exactly that (a gantry's stop below max_misalignment).
    const double locked = slipped_[s] ? r_.settings.axes[s].max_misalignment_mm + kRackingTolerance_mm : 1e-6;
    const double limit =
        in_window ? r_.settings.axes[s].max_misalignment_mm + kRackingTolerance_mm + late_allowance_[s] : locked;
    if (in_window) {
      const AxisStatus& ss_now = r_.status().axes[s];
      const AxisStatus& ms_now = r_.status().axes[mi];
      if (!ss_now.homed || !ms_now.homed) {
        pair_unhomed_seen_[s] = true;
      } else if (pair_unhomed_seen_[s]) {
        square_[s] = rel;  // assigned: square from here
        square_uncertain_[s] = false;
        pair_unhomed_seen_[s] = false;
      }
      // Both sides assigned their home in this cycle (the engine's square,
      // gantry_guard.cpp), though the cycle may still fail before its end
      // marks them homed: square from here too (seed 189001276 of the
      // release run: squared and assigned in step 2, stopped by an alarm in
      // step 3, the next cycle's racking counted from the squared pair).
      const auto under_way = [](Phase p) { return p != Phase::done && p != Phase::idle; };
      if (under_way(ss_now.phase) || under_way(ms_now.phase)) {
        pair_under_way_[s] = true;
      } else if (pair_under_way_[s] && ss_now.phase == Phase::done && ms_now.phase == Phase::done) {
        square_[s] = rel;
        square_uncertain_[s] = false;
        pair_under_way_[s] = false;
      }
      // After lost steps or a slip (before this window or in it: a side's
      // drive faulted, the other brakes on) the module's square is not the
      // carriages': they may stand as far out as the limit, either way.
      const double r0 = rack0_[s];
      const double unsure = rack0_uncertain_[s] || square_uncertain_[s] ? limit : 0.0;
      const double low = std::min(-limit, r0 - kRackingTolerance_mm) - r0 - unsure;
      const double high = std::max(limit, r0 + kRackingTolerance_mm) - r0 + unsure;
      dev = signed_dev < low ? low - signed_dev + limit : (signed_dev > high ? signed_dev - high + limit : 0.0);
    }
    // Locked and homed, both sides have the same machine position (each was
    // assigned the master's home position at its own rest point).
    const AxisStatus& ss = r_.status().axes[s];
    const AxisStatus& ms_st = r_.status().axes[mi];
    if (!in_window && ss.homed && ms_st.homed && truth[s].valid && truth[mi].valid &&
        std::abs(ss.position_mm - ms_st.position_mm) > truth[s].tol + truth[mi].tol + 1e-6) {
      std::ostringstream o;
      o << "slave " << kAxisUpper[s] << " at " << ss.position_mm << ", master " << kAxisUpper[mi] << " at "
        << ms_st.position_mm;
      fail("a locked gantry's two sides disagree on their machine position", o.str());
    }
    if (dev > limit) {
      std::ostringstream o;
      o << "slave " << kAxisUpper[s] << " vs master " << kAxisUpper[mi] << ": " << signed_dev << " from "
        << (in_window ? "where the cycle started" : "where the pair was locked") << ", allowed " << limit
        << (in_window ? " from square; the window found it " + std::to_string(rack0_[s]) + " out of square" : "") << "; "
        << fmt_axis(mi, r_, r_.actual(mi)) << "; " << fmt_axis(s, r_, r_.actual(s));
      std::string topology = r_.settings.axes[s].slave_mode == SlaveMode::external_commutator ? " (external commutator" : " (software-slaved";
      topology += m_.plan[s].differs ? ", the slave's own inherited fields differ)" : ")";
      fail((in_window ? "a gantry racked beyond its max misalignment" : "a locked gantry racked outside a cycle") + topology, o.str());
    }
  }
}

void Watch::track_edges(std::size_t a) {
  // A commutator slave's reference is the edge it finds alone, with the
  // commutator on; its compensation move may cross its sensor again, and the
  // pair's pull-off releases it once more with the commutator off.
  if (m_.plan[a].role == Role::slave && r_.settings.axes[a].slave_mode == SlaveMode::external_commutator &&
      !r_.engine.outputs().axes[static_cast<std::size_t>(m_.plan[a].partner)].commutator_output)
    return;
  if (auto e = r_.sim().last_edge(a, false); e && e->time_s >= window_start_s) {
    release_[a] = e->actual_mm;
    has_release_[a] = true;
  }
  if (auto e = r_.sim().last_edge(a, true); e && e->time_s >= window_start_s) {
    trigger_[a] = e->actual_mm;
    has_trigger_[a] = true;
  }
}

bool Watch::reference_edge(std::size_t a, double& ref) {
  AxisSettings e = effective(r_.settings, a);
  e.mode = squaring_mode(r_.settings, a);
  if (mode_reapproaches(e.mode)) {
    ref = trigger_[a];
    return has_trigger_[a];
  }
  if (!has_release_[a]) return false;
  ref = release_[a];
  if (e.mode == HomingMode::switch_index) {
    // The first index pulse beyond the release edge, away from the sensor.
    const auto& c = r_.sim().axis_config(a);
    const double dir = dir_of(e);
    if (c.index_pitch_mm <= 0) return false;
    const double k = dir < 0 ? std::floor((ref - c.index_offset_mm) / c.index_pitch_mm) + 1
                             : std::ceil((ref - c.index_offset_mm) / c.index_pitch_mm) - 1;
    ref = c.index_offset_mm + k * c.index_pitch_mm;
  }
  return true;
}

void Watch::assign_unsequenced() {
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((plan.unsequenced & axis_bit(a)) && !(flipped & axis_bit(a)) && r_.status().axes[a].homed) on_flip(a, r_.actual(a));
}

void Watch::on_flip(std::size_t a, double x) {
  const AxisMask bit = axis_bit(a);
  flipped |= bit;
  const AxisSettings e = effective(r_.settings, a);
  const AxisStatus& as = r_.status().axes[a];
  const auto& c = r_.sim().axis_config(a);
  Truth t;
  t.valid = true;
  if (!(plan.covered & bit) && !(plan.unsequenced & bit)) {
    fail("an axis outside the cycle was homed", fmt_axis(a, r_, x));
    return;
  }
  if (mode_is_absolute(e.mode)) {
    t.offset = c.absolute_offset_mm - e.home_position_mm;
  } else if (plan.unsequenced & bit) {
    t.offset = e.home_position_mm - x;
  } else if (e.mode == HomingMode::manual) {
    t.offset = e.home_position_mm - window_start_x[a];
  } else if (e.mode == HomingMode::hard_stop) {
    // Pull-off away from the stop it homes against, whatever steps were lost there.
    const double stop = dir_of(e) < 0 ? c.hard_stop_min_mm : c.hard_stop_max_mm;
    t.rest = rig::rest_point_mm(e, stop);
    t.has_rest = true;
    t.offset = e.home_position_mm - t.rest;
    t.tol = 1e-6;
  } else if (e.mode == HomingMode::drive) {
    // home_position where the drive's own homing ends.
    t.offset = e.home_position_mm - std::clamp(c.drive_home_position_mm, c.hard_stop_min_mm, c.hard_stop_max_mm);
  } else {
    // A sensor forced to a level during the cycle makes exactly the edge
    // some phase looks for: dead (stuck inactive, an open NO circuit) looks
    // like a release edge, stuck on (stuck active, an open NC circuit) like
    // a trigger. Where the fault forces the kind of edge this mode homes on,
    // no engine can tell it from the cam: no truth to hold it to. Otherwise
    // a homed axis must be right whatever happened.
    AxisSettings sq = e;
    sq.mode = squaring_mode(r_.settings, a);
    const bool homes_on_trigger = mode_reapproaches(sq.mode);
    if ((tampered & bit) && (homes_on_trigger ? (stuck_on & bit) : (dead_sensor & bit))) return;
    double ref = 0;
    if (!reference_edge(a, ref)) {
      fail("homed without the sensor edge its mode uses", fmt_axis(a, r_, x));
      return;
    }
    const double comp = master_index(r_.settings, a) >= 0 ? e.switch_compensation_mm : 0.0;
    t.rest = rest_from_edge(e, ref, comp);
    t.has_rest = true;
    t.offset = e.home_position_mm - t.rest;
    t.tol = rig::edge_tolerance_mm(e, 0.001) + 1e-9;
  }
  truth[a] = t;
  const double pos = x + t.offset;
  if (std::abs(as.position_mm - pos) > t.tol + 1e-6) {
    std::ostringstream o;
    o << fmt_axis(a, r_, x) << "; the truth is " << pos;
    if (t.has_rest) o << " (reference edge at rest point " << t.rest << ")";
    std::string kind = (plan.unsequenced & bit) ? "unsequenced " : "";
    if (master_index(r_.settings, a) >= 0)
      kind += r_.settings.axes[a].slave_mode == SlaveMode::external_commutator ? "commutator slave, " : "software slave, ";
    kind += std::string(mode_name(e.mode));
    if (m_.plan[a].differs) kind += ", its own inherited fields differ";
    fail("homed with a coordinate other than its mode defines (" + kind + ")", o.str());
    truth[a].valid = false;  // one failure, not one per period after it
  }
}

}  // namespace campaign
