// The failure policy (global.failure_policy, docs/homing-methods.md "Failure
// policy"): what a homing cycle does once an axis has failed or the cycle was
// aborted. stop_all stops every axis at once (halt). finish_independent stops
// the failed axes and their gantry partners and lets the other axes of the
// running step finish their homing; no later step starts. return_to_start
// brakes every axis, then sends each axis that moved in the cycle and may
// move safely back to where the cycle found it, step by step, the last step
// first. Whatever the policy, a machine-wide cause stops everything, and a
// failure while the axes go back (after the period of the first) stops them
// where they are.
#include <algorithm>
#include <cmath>

#include "engine.hpp"
#include "gantry.hpp"

namespace homing {
namespace {

// Causes that concern the whole machine, not one axis: no axis may go on.
bool stops_everything(AlarmCode code) {
  switch (code) {
    case AlarmCode::emergency_stop:
    case AlarmCode::communication_lost:  // the host that started the motion is gone
    case AlarmCode::permit_withdrawn:    // a guard door, an interlock: nothing may home
    case AlarmCode::settings_lost:
      return true;
    default:
      return false;
  }
}

// An axis with an alarm of its own goes back only when the alarm says it
// never ran past where its sensor should have stopped it, and its drive,
// limits and mechanism are as they were: an abort, or a search that went
// wrong away from the sensor (not_released, index_not_found,
// switch_not_repeatable). Not after a seek or stop that ran on without its
// sensor (sensor_not_found, overrun_during_stop, stop_distance_exceeded,
// reapproach_not_found: it may have met its mechanical stop and lost
// steps there), a drive fault (its steps went nowhere), a limit or soft
// limit (it stands at the end of its travel), a racked gantry
// (misalignment), a locking indexer's fault (the pin may be in), an
// encoder or a stop it could not tell (hard-stop and drive methods).
bool alarm_lets_return(AlarmCode code) {
  switch (code) {
    case AlarmCode::none:
    case AlarmCode::aborted:
    case AlarmCode::not_released:
    case AlarmCode::index_not_found:
    case AlarmCode::switch_not_repeatable:
      return true;
    default:
      return false;
  }
}

// The feedrate of the way back: the lower of the axis's jog and seek
// feedrates (a slave moves with its master's), both speeds the machine was
// commissioned to run at.
double return_speed_mm_per_s(const AxisSettings& s) {
  double v = 0;
  for (const double f : {s.jog_feedrate_mm_per_min, s.seek_feedrate_mm_per_min})
    if (f > 0) v = v > 0 ? std::min(v, f) : f;
  return mm_per_min_to_mm_per_s(v);
}

}  // namespace

// The policy for an alarm just latched, as the cycle stands: none (every
// axis stops) when no step runs, in a reference check, the cause concerns the whole machine, the
// axes are already going back, or the policy is stop_all. Alarms latched in
// the period the failure came are one failure: the way back is planned
// again with them all.
Engine::WindDown Engine::wind_down_for(const Settings& settings, AlarmCode code) const {
  const bool step_runs = cycle_active_ && step_index_ >= 0 && step_index_ < static_cast<int>(plan_.steps.size());
  // A reference check is no homing cycle: one short move at latch speed,
  // stopped where it is whatever the policy.
  if (!step_runs || cycle_is_check_ || stops_everything(code)) return WindDown::none;
  if (wind_down_ == WindDown::returning)
    return heartbeat_ == wind_down_period_ ? WindDown::returning : WindDown::none;
  if (wind_down_ == WindDown::finishing) return WindDown::finishing;
  switch (settings.global.failure_policy) {
    case FailurePolicy::stop_all: return WindDown::none;
    case FailurePolicy::finish_independent: return WindDown::finishing;
    case FailurePolicy::return_to_start: return WindDown::returning;
  }
  return WindDown::none;
}

// global.alarm_clears_homed applies as to any alarm, except that the homing
// of the axes finish_independent lets go on (done or not) stands.
void Engine::after_alarm(const Settings& settings, AlarmCode code) {
  const WindDown next = wind_down_for(settings, code);
  if (next == WindDown::none) return halt(settings);
  if (wind_down_ == WindDown::none) wind_down_period_ = heartbeat_;
  if (next == WindDown::returning) {
    unhome_on_alarm(settings);
    return begin_return(settings);
  }
  finish_independent(settings);
  AxisMask going_on = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (axes_[a].in_cycle) going_on |= axis_bit(a);
  unhome_on_alarm(settings, going_on);
}

// An axis depends on another when it is its gantry partner: the failed axes
// and their partners stop. The other axes of the running step go on with
// their homing (run_cycle ends the cycle once they are done), the axes of
// the steps after it never start, and those of the steps before it are done.
void Engine::finish_independent(const Settings& settings) {
  wind_down_ = WindDown::finishing;
  const AxisMask step = plan_.steps[static_cast<std::size_t>(step_index_)];
  AxisMask stopped = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!axes_[a].alarm) continue;
    stopped |= axis_bit(a);
    if (const int p = gantry_partner(settings, a); p >= 0) stopped |= axis_bit(static_cast<std::size_t>(p));
  }
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    if (stopped & axis_bit(a)) {
      stop_axis(settings, a);
    } else if (run.in_cycle && !(step & axis_bit(a))) {
      run.in_cycle = false;
      if (run.phase != Phase::done) run.set_phase(Phase::idle);
    }
  }
}

// Every axis brakes at once. Those that go back hold in return_to_start
// (the running step's) or waiting (an earlier step's, for its turn), and
// lose the home this cycle gave them: the way back undoes the cycle. The
// others stop and leave the cycle.
void Engine::begin_return(const Settings& settings) {
  wind_down_ = WindDown::returning;
  const AxisMask back = returning_axes(settings);
  const AxisMask step = plan_.steps[static_cast<std::size_t>(step_index_)];
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    if (!(back & axis_bit(a))) {
      stop_axis(settings, a);
      continue;
    }
    run.command = stop_command(settings.axes[a].acceleration_mm_per_s2);
    run.home.reset();
    run.aligning = false;
    // One output drives both motors of a commutator pair: its slave rides
    // with its master. A software-slaved slave goes back on its own output.
    run.follow_master = is_commutator_slave(settings, a);
    run.set_phase((step & axis_bit(a)) ? Phase::return_to_start : Phase::waiting);
  }
}

// The axes that go back: each axis of the cycle whose motor moved, whose
// counted steps are its carriage's travel, and whose own alarm (if any)
// lets it move; a gantry pair both sides or neither.
AxisMask Engine::returning_axes(const Settings& settings) const {
  AxisMask back = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (may_return(settings, a)) back |= axis_bit(a);
  AxisMask moved = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (axes_[a].moved_in_cycle) moved |= axis_bit(a);
  AxisMask out = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisMask group = axis_bit(a);
    if (const int p = gantry_partner(settings, a); p >= 0) group |= axis_bit(static_cast<std::size_t>(p));
    if ((back & group) == group && (moved & group)) out |= axis_bit(a);
  }
  return out;
}

bool Engine::may_return(const Settings& settings, std::size_t a) const {
  const AxisRun& run = axes_[a];
  // One that started on a limit switch stands at the end of its travel: its
  // way back would end on the switch (campaign seed 162).
  return run.in_cycle && !run.steps_off_carriage && !run.started_on_limit && alarm_lets_return(run.alarm.code) &&
         return_speed_mm_per_s(settings.axes[a]) > 0 && settings.axes[a].acceleration_mm_per_s2 > 0;
}

// One period of the way back: the axes of the returning step move once
// every motor has come to rest (and no commutator still hands an output to
// a slave motor); when all of them are back, the step before goes next.
void Engine::run_return(const Settings& settings) {
  AxisMask now = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (axes_[a].phase == Phase::return_to_start) now |= axis_bit(a);
  if (!now) {
    if (!next_return_step()) return end_wind_down();
    return run_return(settings);
  }
  const bool all_at_rest = std::none_of(axes_.begin(), axes_.end(), [](const AxisRun& r) {
    return r.moving() || r.commutator_output;
  });
  bool back = true;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (now & axis_bit(a)) back = return_axis(settings, a, all_at_rest) && back;
  if (!back) return;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (now & axis_bit(a)) axes_[a].set_phase(Phase::idle);  // in the cycle until its end
}

// The latest earlier step with axes waiting to go back: they go next.
bool Engine::next_return_step() {
  while (--step_index_ >= 0) {
    const AxisMask step = plan_.steps[static_cast<std::size_t>(step_index_)];
    bool any = false;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if ((step & axis_bit(a)) && axes_[a].in_cycle && axes_[a].phase == Phase::waiting) {
        axes_[a].set_phase(Phase::return_to_start);
        any = true;
      }
    if (any) return true;
  }
  return false;
}

// The phase return_to_start of one axis: brake, wait for every motor to
// rest, then move to the motor position the cycle started from. Both sides
// of a software-slaved gantry set off in the same period with the same
// feedrate and acceleration, so their skew goes straight back to the one
// they started with (the gantry guard still watches it). True once back.
bool Engine::return_axis(const Settings& settings, std::size_t a, bool all_at_rest) {
  AxisRun& run = axes_[a];
  if (const int m = gantry_master(settings, a); m >= 0 && is_commutator_slave(settings, a)) {
    const AxisRun& master = axes_[static_cast<std::size_t>(m)];
    const auto* going = master.phase_data_if<phase_data::Return>();
    return going && going->under_way && !master.moving() &&
           std::abs(master.motor.position_mm - master.target_mm) <= 1e-9;
  }
  const AxisSettings& s = settings.axes[a];
  auto& going = run.phase_data<phase_data::Return>();
  if (!going.under_way) {
    run.command = stop_command(s.acceleration_mm_per_s2);
    if (!all_at_rest) return false;
    going.under_way = true;
    run.target_mm = run.cycle_start_mm;
    run.phase_start_mm = run.motor.position_mm;
  }
  run.command = move_to_command(run.motor, run.target_mm, return_speed_mm_per_s(s), s.acceleration_mm_per_s2,
                                last_dt_s_);
  return !run.moving() && std::abs(run.motor.position_mm - run.target_mm) <= 1e-9;
}

// The failed cycle is over: not counted, no unsequenced axis assigned.
void Engine::end_wind_down() {
  for (AxisRun& run : axes_) {
    run.in_cycle = false;
    if (run.phase == Phase::waiting) run.set_phase(Phase::idle);
  }
  cycle_active_ = false;
  step_index_ = -1;
  wind_down_ = WindDown::none;
}

}  // namespace homing
