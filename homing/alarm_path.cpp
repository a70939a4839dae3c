// The alarm path: the only code that latches or clears an alarm, and what an
// alarm does (alarm_clears_homed; every axis stops, or the failure policy
// winds the cycle down: failure_policy.cpp). Abort and reset are the
// commands that act on it.
#include <algorithm>
#include <bit>

#include "engine.hpp"

namespace homing {

// The one way an axis alarm is latched. Each axis of `axes` that has none
// yet takes `alarm`, stamped with the phase it is in: the first alarm on an
// axis names the cause and later ones change nothing; the first axis to
// latch one stays the machine's first (status.alarm_axis) until a reset.
// Once any axis has latched (all of `axes` first, so each keeps the phase it
// was in), global.alarm_clears_homed applies and every axis stops, or the
// failure policy says what the running cycle does instead. While a failure
// policy moves an axis that already has its alarm (an aborted axis going
// back), a new cause on it (a drive fault, a lost link) acts all the same,
// the axis keeping its first alarm; the same cause raised again (a drive
// fault still present) does not, nor one on an axis the policy stopped.
void Engine::raise(const Settings& settings, AxisMask axes, Alarm alarm) {
  bool latched = false;
  bool new_cause = false;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    if (!(axes & axis_bit(a))) continue;
    if (run.alarm) {
      new_cause = new_cause || (run.in_cycle && run.alarm.code != alarm.code);
      continue;
    }
    run.alarm = alarm;
    run.alarm.phase = run.shown_phase();
    if (first_alarm_axis_ < 0) first_alarm_axis_ = static_cast<int>(a);
    raised_now_ |= axis_bit(a);
    latched = true;
  }
  if (latched || (new_cause && wind_down_ != WindDown::none)) after_alarm(settings, alarm.code);
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
  unhome_on_alarm(settings);
  stop_all(settings);
}

// global.alarm_clears_homed: every axis but those a failure policy lets
// finish their homing (failure_policy.cpp) is no longer homed.
void Engine::unhome_on_alarm(const Settings& settings, AxisMask spared) {
  if (!settings.global.alarm_clears_homed) return;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (!(spared & axis_bit(a))) axes_[a].lose_reference();
}

void Engine::stop_all(const Settings& settings) {
  for (std::size_t a = 0; a < kAxisCount; ++a) stop_axis(settings, a);
  cycle_active_ = false;
  cycle_is_check_ = false;
  step_index_ = -1;
  wind_down_ = WindDown::none;
}

void Engine::stop_axis(const Settings& settings, std::size_t a) {
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
  run.measuring = false;
  run.aligning = false;
  if (moving) run.set_phase(Phase::stopping);
  else if (run.phase != Phase::done) run.set_phase(Phase::idle);
}

// Only alarms latched before this period: one raised in the period the
// reset arrives (a limit tripped as the operator pressed reset for something
// else) has not been published yet and stays, or the cycle would end with
// no reason given.
void Engine::clear_alarms() {
  if (!global_raised_now_) global_alarm_ = AlarmCode::none;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (!(raised_now_ & axis_bit(a))) axes_[a].alarm = Alarm{};
  // The first alarm stays the first if it is one of those kept.
  if (first_alarm_axis_ >= 0 && !axes_[static_cast<std::size_t>(first_alarm_axis_)].alarm) {
    first_alarm_axis_ = -1;
    for (std::size_t a = 0; a < kAxisCount && first_alarm_axis_ < 0; ++a)
      if (axes_[a].alarm) first_alarm_axis_ = static_cast<int>(a);
  }
}

// Abort during homing is an alarm on every axis still homing, and the
// failure policy applies to it as to any failure: every axis brakes at once
// (no axis is left to finish: each is the aborted one), and under
// return_to_start the axes then go back. An abort while a failed cycle winds
// down stops it where it is, with no alarm of its own (the first stays the
// one reported). Abort of a jog or move just stops it.
void Engine::abort_command(const Settings& settings) {
  ++command_count_;
  const bool winding_down = wind_down_ != WindDown::none;
  if (cycle_active_ && !winding_down) {
    AxisMask homing = 0, moving = 0;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (axes_[a].in_cycle && axes_[a].phase != Phase::done) {
        homing |= axis_bit(a);
        if (axes_[a].phase != Phase::waiting) moving |= axis_bit(a);
      }
    const bool first = first_alarm_axis_ < 0;
    raise(settings, homing, Alarm{AlarmCode::aborted});
    // The axis shown as the machine's first (status.alarm_axis) is one the
    // abort stopped, not one waiting for its step of the sequence.
    if (first && moving)
      first_alarm_axis_ = static_cast<int>(std::countr_zero(static_cast<unsigned>(moving)));
  }
  const bool goes_back = !winding_down && wind_down_ == WindDown::returning;
  if (!goes_back) stop_all(settings);
  last_result_ = CommandResult::accepted;
}

// Reset is refused while its cause is still present, and while a failed
// cycle winds down (the alarm that started it stays until the axes rest;
// abort stops it).
CommandResult reset_refusal_of(std::uint16_t interlocks) {
  using namespace interlock;
  if (interlocks & (estop | drive_fault | communication_lost)) return CommandResult::refused_cause_present;
  return CommandResult::accepted;
}

void Engine::reset_command() {
  ++command_count_;
  std::uint16_t causes = 0;
  if (estop_) causes |= interlock::estop;
  if (any_drive_fault()) causes |= interlock::drive_fault;
  if (heartbeat_stale_) causes |= interlock::communication_lost;
  if (const CommandResult r = reset_refusal_of(causes); r != CommandResult::accepted) {
    last_result_ = r;
  } else if (wind_down_ != WindDown::none) {
    last_result_ = CommandResult::refused_busy;
  } else {
    clear_alarms();
    last_result_ = CommandResult::accepted;
  }
}

}  // namespace homing
