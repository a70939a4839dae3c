// The alarm path: the only code that latches or clears an alarm, and what an
// alarm does (every axis stops, alarm_clears_homed). Abort and reset are the
// commands that act on it.
#include <algorithm>

#include "engine.hpp"

namespace homing {

// The one way an axis alarm is latched. Each axis of `axes` that has none
// yet takes `alarm`, stamped with the phase it is in: the first alarm on an
// axis names the cause and later ones change nothing. Once any axis has
// latched (all of `axes` first, so each keeps the phase it was in), every
// axis stops and global.alarm_clears_homed applies.
void Engine::raise(const Settings& settings, AxisMask axes, Alarm alarm) {
  bool latched = false;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    if (!(axes & axis_bit(a)) || run.alarm) continue;
    run.alarm = alarm;
    run.alarm.phase = run.shown_phase();
    raised_now_ |= axis_bit(a);
    latched = true;
  }
  if (latched) halt(settings);
}

// An alarm not tied to one axis (e-stop, settings lost): latched once, and
// every period it is raised motion stops as for an axis alarm.
void Engine::raise_global(const Settings& settings, AlarmCode code) {
  if (global_alarm_ == AlarmCode::none) {
    global_alarm_ = code;
    global_raised_now_ = true;
  }
  halt(settings);
}

void Engine::halt(const Settings& settings) {
  if (settings.global.alarm_clears_homed) {
    for (AxisRun& run : axes_) run.lose_reference();
  }
  stop_all(settings);
}

void Engine::stop_all(const Settings& settings) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    run.command = stop_command(settings.axes[a].acceleration_mm_per_s2);
    const bool moving = run.motor.velocity_mm_per_s != 0;
    // A push cut short brakes on toward (or into) the stop it was pushing
    // into: the current stays reduced until the motor rests (phase stopping).
    if (!moving) run.push_output = false;
    // The commutator is switched back by release_commutators once the slave
    // motor is at rest: switching it under a moving motor would hand the
    // pulses to the other motor.
    run.in_cycle = false;
    run.checking = false;
    run.aligning = false;
    if (moving) run.set_phase(Phase::stopping);
    else if (run.phase != Phase::done) run.set_phase(Phase::idle);
  }
  cycle_active_ = false;
  cycle_is_check_ = false;
  step_index_ = -1;
}

// Only alarms latched before this period: one raised in the period the
// reset arrives (a limit tripped as the operator pressed reset for something
// else) has not been published yet and stays, or the cycle would end with
// no reason given.
void Engine::clear_alarms() {
  if (!global_raised_now_) global_alarm_ = AlarmCode::none;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (!(raised_now_ & axis_bit(a))) axes_[a].alarm = Alarm{};
}

// Abort during homing is an alarm on every axis still homing; abort of a
// jog or move just stops it.
void Engine::abort_command(const Settings& settings) {
  ++command_count_;
  if (cycle_active_) {
    AxisMask homing = 0;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (axes_[a].in_cycle && axes_[a].phase != Phase::done) homing |= axis_bit(a);
    raise(settings, homing, Alarm{AlarmCode::aborted});
  }
  stop_all(settings);
  last_result_ = CommandResult::accepted;
}

// Reset is refused while its cause is still present.
void Engine::reset_command() {
  ++command_count_;
  if (estop_ || any_drive_fault() || comm_lost_) {
    last_result_ = CommandResult::refused_cause_present;
  } else {
    clear_alarms();
    last_result_ = CommandResult::accepted;
  }
}

}  // namespace homing
