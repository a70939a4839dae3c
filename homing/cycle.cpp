// The homing cycle: refused or started, then run step by step along its
// plan (sequence.hpp), each axis through its phases (axis_phases.cpp), and
// finished by assigning the unsequenced axes.
#include <algorithm>

#include "engine.hpp"
#include "gantry.hpp"

namespace homing {

CommandResult homing_refusal_of(std::uint16_t interlocks) {
  using namespace interlock;
  if (interlocks & estop) return CommandResult::refused_estop;
  if (interlocks & drive_fault) return CommandResult::refused_drive_fault;
  if (interlocks & (alarm_latched | settings_lost)) return CommandResult::refused_alarm;
  if (interlocks & communication_lost) return CommandResult::refused_communication_lost;
  if (interlocks & permit_missing) return CommandResult::refused_no_permit;
  if (interlocks & (homing_active | motion_active)) return CommandResult::refused_busy;
  return CommandResult::accepted;
}

CommandResult Engine::homing_refusal(const Settings& settings) const {
  std::uint16_t blocking = 0;
  if (estop_) blocking |= interlock::estop;
  if (any_drive_fault()) blocking |= interlock::drive_fault;
  if (any_alarm()) blocking |= interlock::alarm_latched;
  if (comm_lost_) blocking |= interlock::communication_lost;
  if (settings.global.permit_required && !permit_) blocking |= interlock::permit_missing;
  if (any_motion()) blocking |= interlock::motion_active;
  return homing_refusal_of(blocking);
}

void Engine::home_command(const Settings& settings, const Inputs& inputs) {
  const Commands& c = inputs.commands;
  // A physical input acts on a press seen after start-up, never on a level
  // held at power-up.
  const bool start_edge = !first_step_ && inputs.start_button && !prev_start_button_;
  prev_start_button_ = inputs.start_button;
  const bool home_all = c.home_all || start_edge;
  const AxisMask home_axes = c.home_axes & kAllAxes;
  if (home_all || home_axes) {
    ++command_count_;
    if (cycle_active_) {
      const bool same =
          !cycle_is_check_ && (home_all ? cycle_all_ : (!cycle_all_ && home_axes == cycle_requested_));
      last_result_ = same ? CommandResult::already_running : CommandResult::refused_busy;
    } else if (const CommandResult r = homing_refusal(settings); r != CommandResult::accepted) {
      last_result_ = r;
    } else if (!home_all && !settings.global.single_axis_homing) {
      last_result_ = CommandResult::refused_home_all_only;
    } else {
      start_cycle(settings, home_all ? kAllAxes : home_axes, home_all);
    }
  }
}

void Engine::start_cycle(const Settings& settings, AxisMask requested, bool all, AxisMask measure) {
  plan_ = plan_cycle(settings, requested, all);
  plan_.unsequenced &= static_cast<AxisMask>(~keeps_coordinate(settings, plan_.unsequenced));
  const AxisMask covered = plan_.covered();
  const AxisMask unsequenced = plan_.unsequenced;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    // In a home-all, a slave's own bit is ignored, so a slave whose slave_of
    // names no usable master (itself, another slave) would never be covered
    // and would silently stay unhomed: check every slave's configuration,
    // and the unsequenced axes that get their position at the end.
    const bool slave = master_of(settings.axes[a]) >= 0;
    const bool involved = (covered | unsequenced) & axis_bit(a);
    const bool names_involved = slave && ((covered | unsequenced) &
                                          axis_bit(static_cast<std::size_t>(std::clamp(master_of(settings.axes[a]), 0, 5))));
    if (!involved && !(all && slave) && !names_involved) continue;
    if (const auto& fault = faults()[a]) {
      raise(settings, axis_bit(fault->axis),
            Alarm{fault->code(), Phase::idle, fault->field, fault->value, static_cast<std::uint8_t>(fault->rule)});
      last_result_ = CommandResult::refused_settings_fault;
      return;
    }
  }

  cycle_active_ = true;
  cycle_is_check_ = false;
  cycle_all_ = all;
  cycle_requested_ = requested;
  step_index_ = -1;
  last_result_ = CommandResult::accepted;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    if (!((covered | unsequenced) & axis_bit(a))) continue;
    // Whether this cycle's home correction can be trusted as a measurement.
    run.homed_at_cycle_start = run.homed();
    if (!(covered & axis_bit(a))) continue;
    run.in_cycle = true;
    run.cycle_start_mm = run.motor.position_mm;
    run.steps_off_carriage = false;
    run.moved_in_cycle = false;
    run.started_on_limit = run.readings.limit_min || run.readings.limit_max;
    // A full cycle replaces any reference check the axis was offered.
    run.lose_reference();
    run.homed_by_check = false;
    run.checking = false;
    run.measuring = (measure & axis_bit(a)) != 0;
    run.drive_referenced = false;
    run.set_phase(Phase::waiting);  // for its step
    run.entered = false;
    run.reached = Reached::nothing;
    run.aligning = false;
    run.follow_master = false;
  }
  for (std::size_t sl = 0; sl < kAxisCount; ++sl) {
    const int m = gantry_master(settings, sl);
    if (m < 0) continue;
    AxisRun& slave = axes_[sl];
    slave.pair_rel0_mm = slave.motor.position_mm - axes_[static_cast<std::size_t>(m)].motor.position_mm;
    if (!slave.pair_square_mm || slave.pair_square_master != m) {
      slave.pair_square_mm = slave.pair_rel0_mm;
      slave.pair_square_master = m;
    }
  }
  start_step(settings);
}

bool Engine::start_step(const Settings& settings) {
  while (++step_index_ < static_cast<int>(plan_.steps.size())) {
    const AxisMask mask = plan_.steps[static_cast<std::size_t>(step_index_)];
    if (!mask) continue;
    // An alarm raised as an axis begins may have stopped others of the step.
    for (std::size_t a = 0; a < kAxisCount && steps_run(); ++a)
      if ((mask & axis_bit(a)) && axes_[a].in_cycle) begin_axis(settings, a);
    return true;
  }
  finish_cycle(settings);
  return false;
}

// The running step's axes each run their phase. Once all of them are done
// the next step starts; after a failure under finish_independent (the axes
// the failure stopped have left the cycle) the cycle ends there instead, and
// under return_to_start the axes go back (failure_policy.cpp).
void Engine::run_cycle(const Settings& settings) {
  if (!cycle_active_ || step_index_ < 0) return;
  if (wind_down_ == WindDown::returning) return run_return(settings);
  const AxisMask mask = plan_.steps[static_cast<std::size_t>(step_index_)];
  for (std::size_t a = 0; a < kAxisCount && steps_run(); ++a)
    if ((mask & axis_bit(a)) && axes_[a].in_cycle) run_axis(settings, a);
  if (!steps_run()) return;
  bool all_done = true;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((mask & axis_bit(a)) && axes_[a].in_cycle && axes_[a].phase != Phase::done) all_done = false;
  if (!all_done) return;
  if (wind_down_ == WindDown::finishing) end_wind_down();
  else start_step(settings);
}

// An unsequenced axis already homed keeps its coordinate in a home-all: were it
// assigned where it stands again, its soft limits would move with it, and jog,
// home-all, jog would creep toward the stop. Only an absolute axis reads its
// encoder again (that never creeps); a single-axis home that names the axis
// (not unsequenced then) assigns it afresh. A slave keeps it with its master.
AxisMask Engine::keeps_coordinate(const Settings& settings, AxisMask unsequenced) const {
  AxisMask keep = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(unsequenced & axis_bit(a))) continue;
    const int m = gantry_master(settings, a);
    const std::size_t owner = m >= 0 ? static_cast<std::size_t>(m) : a;
    const bool from_encoder = mode_row(settings.axes[owner].mode).coordinate == Coordinate::absolute_encoder;
    if (!from_encoder && axes_[owner].homed() && axes_[a].homed()) keep |= axis_bit(a);
  }
  // A pair is kept or assigned together.
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (const int m = gantry_master(settings, a); m >= 0 && (unsequenced & axis_bit(a)) &&
                                                  ((keep >> m) & 1u) != ((keep >> a) & 1u))
      keep &= static_cast<AxisMask>(~(axis_bit(a) | axis_bit(static_cast<std::size_t>(m))));
  return keep;
}

// An axis in no sequence step is given its coordinate where it stands (MASSO);
// an absolute axis always takes it from its encoder.
void Engine::assign_unsequenced(const Settings& settings, std::size_t a) {
  AxisRun& run = axes_[a];
  const std::optional<double> machine_now = run.coordinate_where_it_stands(settings.axes[a]);
  if (!machine_now) return raise(settings, axis_bit(a), Alarm{AlarmCode::encoder_fault});
  const double new_offset = *machine_now - run.motor.position_mm;
  run.home_correction_mm = new_offset - run.offset_mm;
  run.trigger_position_mm = run.motor.position_mm + run.offset_mm;
  run.offset_mm = new_offset;
  run.home = home_frame(settings.axes[a]);
  run.homed_by_check = false;
  run.restored.reset();
  run.set_phase(Phase::done);
}

// The steps are done: the axes in no step are given their coordinate. A
// failure here (an absolute axis's invalid encoder) fails the cycle as one in
// its last step would: its failure policy applies from the last step.
void Engine::finish_cycle(const Settings& settings) {
  step_index_ = static_cast<int>(plan_.steps.size()) - 1;
  for (std::size_t a = 0; a < kAxisCount && cycle_active_ && wind_down_ == WindDown::none; ++a)
    if (plan_.unsequenced & axis_bit(a)) assign_unsequenced(settings, a);
  if (!cycle_active_ || wind_down_ != WindDown::none) return;  // an encoder fault failed the cycle
  for (AxisRun& run : axes_) {
    // A refused reference check leaves its axis at rest, not homed: idle, not done.
    // So does a measurement that pushed into a hard stop (its steps lost there).
    if ((run.checking || run.measuring) && !run.homed()) run.set_phase(Phase::idle);
    run.checking = false;
    run.measuring = false;
    run.in_cycle = false;
  }
  cycle_active_ = false;
  step_index_ = -1;
  if (cycle_is_check_) {
    cycle_is_check_ = false;
    return;  // a reference check is not a homing cycle (status.homing_cycles)
  }
  ++homing_cycles_;
}

}  // namespace homing
