// The failure policy as the watch holds the engine to it (docs/homing-methods.md
// "Failure policy", the campaign's own reading in rules.hpp). From the first
// alarm of a running cycle each axis brakes within its stop distance and
// stays, except as the policy says: finish_independent lets the axes of the
// running step that are not the failed ones nor their gantry partners go on
// homing; return_to_start sends each axis of the cycle that moved, whose
// steps count its travel and whose own alarm lets it move, back to where the
// cycle found it (a gantry both sides or neither), the last step first, no
// faster than the lower of its jog and seek feedrates. Alarms latched in one
// period are one failure. A cause that concerns the whole machine, any later
// alarm during the way back and an abort during either stop everything. The
// first alarm stays the one reported.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "verdict.hpp"
#include "watch.hpp"

namespace campaign {
namespace {

std::string where(std::size_t a, rig::Rig& r, double x) {
  std::ostringstream o;
  const AxisStatus& s = r.status().axes[a];
  o << kAxisUpper[a] << " in phase " << phase_name(s.phase) << ", carriage " << x << ", velocity "
    << s.velocity_mm_per_s << ", alarm " << alarm_name(s.alarm.code) << ", at t " << r.sim().time_s();
  return o.str();
}

AxisMask with_partners(const Settings& s, AxisMask m) {
  AxisMask out = m;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (m & axis_bit(a))
      if (const int p = partner_index(s, a); p >= 0) out |= axis_bit(static_cast<std::size_t>(p));
  return out;
}

}  // namespace

// The braking of an axis starts now: from where it was and as fast as it went.
void Watch::brake_from_now(std::size_t a, const Status& st) {
  after[a] = After::brake;
  alarm_v0_[a] = std::max(std::abs(v_prev_[a]), std::abs(st.axes[a].velocity_mm_per_s));
  alarm_x0_[a] = x_prev_[a];
  rested_[a] = false;
  brake_periods_[a] = 0;
}

void Watch::policy_period(const Status& st) {
  AxisMask alarmed = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (st.axes[a].alarm) alarmed |= axis_bit(a);
  // Per axis the first alarm names the cause: it never changes while latched.
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AlarmCode now = st.axes[a].alarm.code;
    if (code_prev_[a] != AlarmCode::none && now != AlarmCode::none && now != code_prev_[a])
      fail("an axis's latched alarm was replaced by another",
           where(a, r_, r_.actual(a)) + "; it was " + std::string(alarm_name(code_prev_[a])));
    code_prev_[a] = now;
  }
  if (!st.alarm) {
    first_axes_ = 0;
  } else if (!alarm_prev_) {
    first_failure(st, alarmed);
  } else {
    const AxisMask newly = alarmed & static_cast<AxisMask>(~alarmed_prev_);
    bool everything = st.global_alarm != AlarmCode::none && global_prev_ == AlarmCode::none;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if ((newly & axis_bit(a)) && stops_everything(st.axes[a].alarm.code)) everything = true;
    // An abort while the policy lets axes go on stops them all, without an alarm of its own.
    if (abort_pending_) everything = true;
    if (newly || everything) later_failure_at(st, everything ? kAllAxes : with_partners(r_.settings, newly));
    if (event_pending_ && wind_down != FailurePolicy::stop_all) later_failure = true;
    // A limit switch met by an axis sent back (its braking carried it onto
    // one: a home cam seeking toward the switch it reverses at) is a new
    // cause on an axis that keeps its first alarm: the way back stops
    // (seed 7201525).
    if (wind_down == FailurePolicy::return_to_start)
      for (std::size_t a = 0; a < kAxisCount; ++a)
        if (after[a] == After::go_back && !started_on_limit_[a] && eff_[a].limits_fitted &&
            (r_.sim().limit_active(a, false) || r_.sim().limit_active(a, true)))
          later_failure = true;
  }
  abort_pending_ = false;
  event_pending_ = false;
  // The first axis to latch stays the one reported until a reset.
  if (st.alarm && !first_axes_) first_axes_ = alarmed;
  // A reset clears every alarm but those latched in its own period, which
  // stay (alarm_path.cpp): when the first ones went that way, the first is
  // among those kept, all latched in that one period (seed 195049782: B's
  // shared limit tripped, then A's with the operator's reset).
  if (st.alarm && !(first_axes_ & alarmed)) first_axes_ = alarmed;
  if (st.alarm && first_axes_) {
    const int f = st.first_alarm_axis;
    if (f < 0 || f >= static_cast<int>(kAxisCount) || !(first_axes_ & axis_bit(static_cast<std::size_t>(f))))
      fail("the first alarm is no longer the one reported (status.alarm_axis)",
           "first latched on " + axis_letters(first_axes_) + ", reported axis " + std::to_string(f));
  }
  for (std::size_t a = 0; a < kAxisCount; ++a) ++brake_periods_[a];
  alarmed_prev_ = alarmed;
  global_prev_ = st.global_alarm;
  homing_prev_ = st.homing;
  step_prev_ = st.sequence_step;
  cycles_prev_ = st.homing_cycles;
}

// The first alarm of a running cycle: what the policy lets each axis do.
void Watch::first_failure(const Status& st, AxisMask alarmed) {
  after.fill(After::brake);
  wind_down = FailurePolicy::stop_all;
  finishers = returners = 0;
  later_failure = false;
  // Every alarm of this period is part of the one failure.
  bool everything = st.global_alarm != AlarmCode::none;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (alarmed & axis_bit(a)) everything = everything || stops_everything(st.axes[a].alarm.code);
  // The script's abort landed in the period of another failure: the engine
  // sees the limit switches and the drives before the commands, so the
  // abort finds the policy at work and stops it where it is (seed 21050675).
  bool aborted_failure = false;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((alarmed & axis_bit(a)) && st.axes[a].alarm.code == AlarmCode::aborted) aborted_failure = true;
  const bool abort_stops_policy = abort_pending_ && !aborted_failure;
  abort_pending_ = false;
  event_pending_ = false;
  // A cycle runs: it ran before this period, or it started in it (an alarm
  // as its first step begins, an absolute axis's invalid encoder).
  // A cycle that completed in this very period (its last step done, counted
  // in status.homing_cycles) is over: a fault raised after it in the same
  // period (an indexer's lock timing out) belongs to no cycle, and every axis
  // stops (seed 21090731).
  const bool completed_now = !st.homing && st.homing_cycles != cycles_prev_;
  if (!in_window || refused || !(homing_prev_ || st.homing) || completed_now || everything) return;
  wind_down = r_.settings.global.failure_policy;
  if (abort_stops_policy) later_failure = true;
  if (wind_down == FailurePolicy::finish_independent) {
    // The step that runs: the one the cycle still shows (an alarm as a step
    // begins belongs to the new step), else the one it showed before.
    const int step = st.homing ? st.sequence_step : step_prev_;
    const AxisMask stopped = with_partners(r_.settings, alarmed);
    AxisMask homing_on = 0;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (plan.step[a] == step && !(stopped & axis_bit(a)) && st.axes[a].phase != Phase::done) homing_on |= axis_bit(a);
    // A pair goes on as one: a slave done with its own part rides with its master's final move.
    finishers = with_partners(r_.settings, homing_on);
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (finishers & axis_bit(a)) after[a] = After::finish;
  } else if (wind_down == FailurePolicy::return_to_start) {
    returners = go_back_rule(st);
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      if (!(returners & axis_bit(a))) continue;
      after[a] = After::go_back;
      // A locking indexer's fault may stop the way back when its axis
      // unlocks or locks, on an axis whose alarm it cannot replace.
      const sim::Fault f = r_.sim().axis_config(a).fault;
      if (f == sim::Fault::indexer_stuck_locked || f == sim::Fault::indexer_never_locks) later_failure = true;
    }
  }
}

// The axes return_to_start sends back: each axis of the cycle that moved in
// it, whose counted steps are its carriage's travel (it never pushed into its
// stop, no drive homed it), that did not start on a limit switch, and whose
// own alarm, if any, lets it move; a gantry pair both sides or neither.
AxisMask Watch::go_back_rule(const Status& st) const {
  AxisMask may = 0, moved = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(plan.covered & axis_bit(a))) continue;
    if (alarm_lets_go_back(st.axes[a].alarm.code) && !steps_off_[a] && !started_on_limit_[a]) may |= axis_bit(a);
    if (path[a] > 1e-9) moved |= axis_bit(a);
  }
  AxisMask out = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisMask pair = with_partners(r_.settings, axis_bit(a));
    if ((may & pair) == pair && (moved & pair)) out |= axis_bit(a);
  }
  return out;
}

// Another alarm (or an abort) after the first: the axes it stops brake from
// now; during the way back, or for a machine-wide cause, all of them.
void Watch::later_failure_at(const Status& st, AxisMask stopped) {
  later_failure = true;
  if (wind_down == FailurePolicy::return_to_start) stopped = kAllAxes;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((stopped & axis_bit(a)) && after[a] != After::brake) brake_from_now(a, st);
}

void Watch::after_alarm(std::size_t a, double x, double v, bool moved) {
  switch (after[a]) {
    case After::brake: return braking(a, x, v);
    case After::finish: return;  // homing on: held to the rules of a running cycle
    case After::go_back: return going_back(a, x, v, moved);
  }
}

void Watch::braking(std::size_t a, double x, double v) {
  const double acc = accel_limit(a);
  if (brake_periods_[a] > 1 && std::abs(v) > std::abs(v_prev_[a]) + 1e-9)
    fail("speed rose while an alarm is latched", where(a, r_, x));
  const double v0 = alarm_v0_[a];
  const double bound = (acc > 0 ? stop_distance_mm(v0, acc) : 0) + v0 * m_.max_dt_s + 1e-6;
  if (std::abs(x - alarm_x0_[a]) > bound) {
    std::ostringstream o;
    o << where(a, r_, x) << "; " << std::abs(x - alarm_x0_[a]) << " since the alarm, stop distance from " << v0
      << " is " << bound;
    fail(wind_down == FailurePolicy::stop_all ? "travelled beyond its stop distance after an alarm"
                                              : "travelled beyond its stop distance after an alarm (failure policy " +
                                                    std::string(name_of(wind_down)) + ")",
         o.str());
  }
  if (rested_[a] && std::abs(x - rest_x_[a]) > 1e-12) fail("motion while an alarm is latched, after rest", where(a, r_, x));
  if (!rested_[a] && v == 0 && !r_.sim().moving(a)) {
    rested_[a] = true;
    rest_x_[a] = x;
  }
}

// Where an axis sent back may end: where the window found it; a commutator
// slave rides back with its master on their one output, keeping the skew
// its motor corrected alone (within its max misalignment).
double Watch::back_tolerance(std::size_t a) const {
  const int m = master_index(r_.settings, a);
  if (m >= 0 && r_.settings.axes[a].slave_mode == SlaveMode::external_commutator)
    return r_.settings.axes[a].max_misalignment_mm + std::abs(rack0_[a]) + kRackingTolerance_mm + late_allowance_[a];
  return 1e-6;
}

bool Watch::back_at_start(std::size_t a, double x) const {
  return std::abs(x - window_start_x[a]) <= back_tolerance(a);
}

// Sent back: braking first, never further from its start than the braking
// takes it; then back, no faster than the lower of its jog and seek
// feedrates, once every axis of a later step is back. (A carriage that met
// its mechanical stop with its motor running on ends past its start by the
// steps lost there: the way back is by counted steps.)
void Watch::going_back(std::size_t a, double x, double v, bool moved) {
  const double start = window_start_x[a];
  const double acc = accel_limit(a);
  const double v0 = alarm_v0_[a];
  const double reach = std::abs(alarm_x0_[a] - start) + (acc > 0 ? stop_distance_mm(v0, acc) : 0) +
                       v0 * m_.max_dt_s + back_tolerance(a) + 1e-6;
  if (std::abs(x - start) > reach && !stop_touched_[a]) {
    std::ostringstream o;
    o << where(a, r_, x) << "; " << std::abs(x - start) << " from where the cycle found it (" << start
      << "), at most " << reach;
    fail("an axis sent back by the failure policy went further away from its start", o.str());
  }
  // At rest once its braking is over: the engine holds every axis still for
  // a period before any goes back, the way back may start within it.
  if (!rested_[a] && v == 0) {
    rested_[a] = true;
    rest_x_[a] = x;
  }
  if (rested_[a] && moved) {
    went_back_[a] = true;
    const double vmax = return_speed(eff_[a]);
    if (std::abs(v) > vmax + 1e-6) {
      std::ostringstream o;
      o << where(a, r_, x) << "; at most " << vmax;
      fail("an axis went back faster than the lower of its jog and seek feedrates", o.str());
    }
    for (std::size_t b = 0; b < kAxisCount; ++b)
      if ((returners & axis_bit(b)) && plan.step[b] > plan.step[a] && !back_[b]) {
        std::ostringstream o;
        o << where(a, r_, x) << " (step " << plan.step[a] << "); " << where(b, r_, r_.actual(b)) << " (step "
          << plan.step[b] << ") is not back yet";
        fail("an axis went back before the axes of a later step were back", o.str());
      }
  }
  back_[a] = v == 0 && !r_.sim().moving(a) && (back_at_start(a, x) || (stop_touched_[a] && went_back_[a]));
}

}  // namespace campaign
