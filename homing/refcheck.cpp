// Position trust across restarts (trust.hpp): the runtime's record of where
// each axis came to rest is taken once at start, and a reference check is
// judged and started as a cycle of its own (its phase: refcheck_phases.cpp).
#include <cmath>

#include "engine.hpp"
#include "gantry.hpp"

namespace homing {

// An axis whose last stop was clean, in the frame its settings give it now,
// takes the stored position as its coordinate: it is not homed, but its
// steps are counted from there, so a jog before the check keeps it right.
// Nothing is taken while an alarm is latched (settings lost at start).
void Engine::restore_last_stops(const Settings& settings, const LastStops& stops) {
  if (any_alarm()) return;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    const LastStop& stop = stops[a];
    if (!stop.clean || !std::isfinite(stop.position_mm) || !mode_homes(settings.axes[a].mode)) continue;
    if (run.homed() || run.in_cycle || run.moving() || run.phase != Phase::idle) continue;
    if (stop.frame != home_frame(settings.axes[a])) continue;
    run.offset_mm = stop.position_mm - run.motor.position_mm;
    run.restored = stop.frame;
  }
}

// What refuses a reference check of one axis beyond what refuses any homing.
CommandResult Engine::refcheck_refusal(const Settings& settings, std::size_t axis) const {
  const AxisSettings& s = settings.axes[axis];
  const AxisRun& run = axes_[axis];
  if (s.mode == HomingMode::disabled) return CommandResult::refused_invalid;
  // One side alone cannot square a pair (docs/homing-methods.md).
  if (gantry_partner(settings, axis) >= 0 || master_of(s) >= 0) return CommandResult::refused_gantry_pair;
  if (!offers_refcheck(s.mode)) return CommandResult::refused_no_switch_edge;
  if (!run.restored || run.homed()) return CommandResult::refused_no_clean_stop;
  if (run.limit_tripped) return CommandResult::refused_hard_limit;
  return CommandResult::accepted;
}

// Judged as a homing command (interlocks, busy), then per axis, then by the
// rule set; any refusal refuses the whole command and moves nothing.
void Engine::refcheck_command(const Settings& settings, AxisMask axes) {
  axes &= kAllAxes;
  ++command_count_;
  if (cycle_active_) {
    last_result_ = cycle_is_check_ && axes == cycle_requested_ ? CommandResult::already_running
                                                               : CommandResult::refused_busy;
    return;
  }
  if (const CommandResult r = homing_refusal(settings); r != CommandResult::accepted) {
    last_result_ = r;
    return;
  }
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(axes & axis_bit(a))) continue;
    if (const CommandResult r = refcheck_refusal(settings, a); r != CommandResult::accepted) {
      last_result_ = r;
      return;
    }
  }
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(axes & axis_bit(a))) continue;
    if (const auto& fault = faults()[a]) {
      raise(settings, axis_bit(fault->axis),
            Alarm{fault->code(), Phase::idle, fault->field, fault->value, static_cast<std::uint8_t>(fault->rule)});
      last_result_ = CommandResult::refused_settings_fault;
      return;
    }
  }
  last_result_ = CommandResult::accepted;
  start_refcheck(axes);
  start_step(settings);
}

// One step holding every axis checked; nothing is assigned at its end.
void Engine::start_refcheck(AxisMask axes) {
  plan_ = CyclePlan{};
  plan_.steps[0] = axes;
  cycle_active_ = true;
  cycle_is_check_ = true;
  cycle_all_ = false;
  cycle_requested_ = axes;
  step_index_ = -1;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(axes & axis_bit(a))) continue;
    AxisRun& run = axes_[a];
    run.in_cycle = true;
    run.checking = true;
    run.homed_at_cycle_start = false;
    run.cycle_start_mm = run.motor.position_mm;
    run.steps_off_carriage = false;
    run.moved_in_cycle = false;
    run.started_on_limit = run.readings.limit_min || run.readings.limit_max;
    run.set_phase(Phase::waiting);
    run.entered = false;
    run.reached = Reached::nothing;
    run.aligning = false;
    run.follow_master = false;
  }
}

}  // namespace homing
