// The engine's period: motion, inputs, safety, commands, homing phases,
// gantries, locking indexers, status and outputs, in that order. Each step has its own file:
// home_frame, sensor_inputs, safety, alarm_path and failure_policy, cycle and axis_phases,
// jog_move, gantry_guard, publish and output_routing.
#include "engine.hpp"

#include <algorithm>
#include <cmath>

#include "gantry.hpp"

namespace homing {

Engine::Engine() = default;

StepResult Engine::step(const Settings& configured, const Inputs& inputs, double dt_s) {
  // Every axis moves with the settings it inherits (a slave its master's).
  const Settings settings = motion_settings(configured);
  // The rule set runs only when a command needs it, not every period.
  configured_ = &configured;
  faults_checked_ = false;
  dt_s = std::isfinite(dt_s) ? std::max(dt_s, 0.0) : 0.0;
  if (dt_s > 0) last_dt_s_ = dt_s;
  ++heartbeat_;
  time_s_ += dt_s;
  raised_now_ = 0;
  global_raised_now_ = false;
  advance_motion(dt_s);
  keep_home_frames(settings);
  read_inputs(settings, inputs, dt_s);
  check_safety(settings, inputs);
  if (inputs.restore) restore_last_stops(settings, *inputs.restore);
  handle_commands(settings, inputs);
  run_cycle(settings);
  run_motion(settings);
  follow_masters(settings);
  guard_gantries(settings);
  release_commutators(settings);
  run_indexers(settings, inputs);  // last word on motion: a locked axis is held
  publish(settings, inputs);
  route_outputs(settings);
  first_step_ = false;
  return StepResult{outputs_, status_};
}

void Engine::advance_motion(double dt_s) {
  for (AxisRun& run : axes_) {
    run.period_start = run.motor;
    run.last_command = run.command;
    run.motor = integrate(run.motor, run.command, dt_s);
    // A period run pushing into the mechanical stop may lose steps, and a
    // drive homing itself moves its carriage without any: from then on the
    // counted steps no longer say how far the carriage went (no way back by
    // them: failure_policy.cpp).
    const bool off = run.phase == Phase::push || run.phase == Phase::push_to_stop || run.phase == Phase::drive_homing;
    if (run.in_cycle && off) run.steps_off_carriage = true;
    if (run.in_cycle && run.motor.position_mm != run.period_start.position_mm) run.moved_in_cycle = true;
  }
}

const SettingsFaults& Engine::faults() const {
  if (!faults_checked_) {
    faults_ = check_settings(*configured_);
    faults_checked_ = true;
  }
  return faults_;
}

bool Engine::any_drive_fault() const {
  return std::any_of(axes_.begin(), axes_.end(), [](const AxisRun& r) { return r.readings.drive_fault; });
}

bool Engine::any_alarm() const {
  if (global_alarm_ != AlarmCode::none) return true;
  return std::any_of(axes_.begin(), axes_.end(), [](const AxisRun& r) { return bool(r.alarm); });
}

bool Engine::any_motion() const {
  return std::any_of(axes_.begin(), axes_.end(), [](const AxisRun& r) {
    return r.motor.velocity_mm_per_s != 0 || r.command.target_velocity_mm_per_s != 0 ||
           r.phase == Phase::jog || r.phase == Phase::move;
  });
}

bool Engine::quiet() const {
  if (cycle_active_ || wind_down_ != WindDown::none) return false;
  for (const AxisRun& run : axes_) {
    // busy(): a cycle, jog, move or stop, motion, an indexer unlocking or locking.
    if (run.busy() || run.command.target_velocity_mm_per_s != 0) return false;
    if (run.phase != Phase::idle && run.phase != Phase::done) return false;
  }
  return std::none_of(inputs_.begin(), inputs_.end(),
                      [](const InputChannel& c) { return c.reset || c.filter.settling(); });
}

// Commands in a fixed order: reset, abort, unhome, set position, home, reference check, measurement, jog, move.
void Engine::handle_commands(const Settings& settings, const Inputs& inputs) {
  const Commands& c = inputs.commands;
  if (c.reset_alarm) reset_command();
  if (c.abort) abort_command(settings);
  if (c.unhome_axes) unhome_command(settings, c.unhome_axes);
  if (c.set_position_axes) set_position_commands(settings, c);
  if (c.abort) {
    cancel_starts(inputs);
    return;
  }
  home_command(settings, inputs);
  if (c.refcheck_axes) refcheck_command(settings, c.refcheck_axes);
  if (c.measure_axes) measure_command(settings, c.measure_axes);
  jog_commands(settings, c);
  move_commands(settings, c);
}

// An abort is never outrun by a start that came with it, in one request (a
// PLC writing its whole command word with FC 15) or from another client in
// the same period: nothing that moves starts in an abort's period. Each start
// is counted and answered cancelled_by_abort; a jog pressed then needs a new
// press, as a jog held at power-up does.
void Engine::cancel_starts(const Inputs& inputs) {
  const Commands& c = inputs.commands;
  const bool start_edge = !first_step_ && inputs.start_button && !prev_start_button_;
  prev_start_button_ = inputs.start_button;
  int cancelled = 0;
  if (c.home_all || start_edge || (c.home_axes & kAllAxes)) ++cancelled;
  if (c.refcheck_axes & kAllAxes) ++cancelled;
  if (c.measure_axes & kAllAxes) ++cancelled;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (c.move_axes & axis_bit(a)) ++cancelled;
    const std::int8_t req = c.jog[a] > 0 ? 1 : (c.jog[a] < 0 ? -1 : 0);
    if (req != 0 && req != axes_[a].prev_jog_request && !first_step_) ++cancelled;
    axes_[a].prev_jog_request = req;
  }
  if (cancelled == 0) return;
  command_count_ += static_cast<std::uint32_t>(cancelled);
  last_result_ = CommandResult::cancelled_by_abort;
}

}  // namespace homing
