// The engine's period: motion, inputs, safety, commands, homing phases, status.
#include "engine.hpp"

#include <algorithm>
#include <cmath>

#include "gantry.hpp"
#include "sequence.hpp"
#include "settings_check.hpp"

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
  advance_motion(dt_s);
  read_inputs(settings, inputs, dt_s);
  check_safety(settings, inputs);
  handle_commands(settings, inputs);
  run_cycle(settings);
  run_motion(settings);
  follow_masters(settings);
  guard_gantries(settings);
  release_commutators(settings);
  publish(settings, inputs);
  first_step_ = false;
  return StepResult{outputs_, status_};
}

void Engine::advance_motion(double dt_s) {
  for (AxisRun& run : axes_) {
    run.period_start = run.motor;
    run.last_command = run.command;
    run.motor = integrate(run.motor, run.command, dt_s);
  }
}

const SettingsFaults& Engine::faults() const {
  if (!faults_checked_) {
    faults_ = check_settings(*configured_);
    faults_checked_ = true;
  }
  return faults_;
}

int Engine::partner_of(const Settings& settings, std::size_t axis) const {
  return gantry_partner(settings, axis);
}

// The input channel an axis reads its home sensor from: a commutator slave's
// sensor is diverted onto its master's input.
int Engine::sensor_channel(const Settings& settings, std::size_t axis) const {
  if (is_commutator_slave(settings, axis)) return gantry_master(settings, axis);
  return static_cast<int>(axis);
}

// The axis whose motor moves the carriage seen on an input channel.
int Engine::channel_owner(const Settings& settings, std::size_t channel) const {
  if (axes_[channel].commutator_output) {
    const int s = gantry_slave(settings, channel);
    if (s >= 0) return s;
  }
  return static_cast<int>(channel);
}

void Engine::read_inputs(const Settings& settings, const Inputs& inputs, double dt_s) {
  const double period_start_s = time_s_ - dt_s;
  for (std::size_t c = 0; c < kAxisCount; ++c) {
    const AxisInputs& in = inputs.axes[c];
    SensorEvent& ev = events_[c];
    ev = SensorEvent{};
    const std::size_t owner_axis = static_cast<std::size_t>(channel_owner(settings, c));
    const AxisRun& owner = axes_[owner_axis];
    // With the commutator on, the master's input carries the slave's switch.
    const bool nc = settings.axes[owner_axis].sensor_nc;
    Debouncer& filter = sensor_filter_[c];
    if (first_step_ || filter_reset_[c]) {
      // A new source on this input (start-up, commutator switched): take its
      // level as it is, without inventing an edge.
      filter.reset(in.sensor_level, time_s_);
      filter_reset_[c] = false;
    } else {
      auto position_at_offset = [&](double tau) {
        return position_at(owner.period_start, owner.last_command, std::clamp(tau, 0.0, dt_s));
      };
      for (std::uint8_t i = 0; i < in.sensor_edges.count; ++i) {
        const double tau = in.sensor_edges.time_s[i];
        filter.transition(period_start_s + tau, position_at_offset(tau));
      }
      // No timestamps, or more edges than reported: the level still wins,
      // placed in the middle of the period.
      if (filter.raw() != in.sensor_level) filter.transition(period_start_s + dt_s / 2, position_at_offset(dt_s / 2));
      AcceptedEdge edge;
      if (filter.settle(time_s_, settings.axes[owner_axis].debounce_ms / 1000.0, edge)) {
        ev.edge = true;
        ev.accepted = edge;
        ev.accepted.to_level = edge.to_level != nc;  // now means "to active"
      }
      if (in.index_edges.count > 0) {
        ev.index = true;
        ev.index_mm = position_at_offset(in.index_edges.time_s[0]);
      }
    }
    axes_[c].sensor_active = filter.stable() != nc;
    drive_fault_[c] = in.drive_fault;
    absolute_valid_[c] = in.absolute_valid;
    absolute_mm_[c] = in.absolute_position_mm;
  }
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

void Engine::stop_all(const Settings& settings) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    run.command = stop_command(settings.axes[a].acceleration_mm_per_s2);
    run.push_output = false;
    // The commutator is switched back by release_commutators once the slave
    // motor is at rest: switching it under a moving motor would hand the
    // pulses to the other motor.
    run.in_cycle = false;
    run.aligning = false;
    const bool moving = run.motor.velocity_mm_per_s != 0;
    if (moving) run.set_phase(Phase::stopping);
    else if (run.phase != Phase::done) run.set_phase(Phase::idle);
  }
  cycle_active_ = false;
  step_index_ = -1;
}

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
    run.alarm.phase = run.phase;
    latched = true;
  }
  if (latched) halt(settings);
}

// An alarm not tied to one axis (e-stop, settings lost): latched once, and
// every period it is raised motion stops as for an axis alarm.
void Engine::raise_global(const Settings& settings, AlarmCode code) {
  if (global_alarm_ == AlarmCode::none) global_alarm_ = code;
  halt(settings);
}

void Engine::halt(const Settings& settings) {
  if (settings.global.alarm_clears_homed) {
    for (AxisRun& run : axes_) run.homed = false;
  }
  stop_all(settings);
}

void Engine::clear_alarms() {
  global_alarm_ = AlarmCode::none;
  for (AxisRun& run : axes_) run.alarm = Alarm{};
}

void Engine::check_safety(const Settings& settings, const Inputs& inputs) {
  if (inputs.estop && !estop_) {
    AxisMask busy = 0;
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      const AxisRun& run = axes_[a];
      if (run.in_cycle || run.motor.velocity_mm_per_s != 0 || run.phase == Phase::jog || run.phase == Phase::move)
        busy |= axis_bit(a);
    }
    raise(settings, busy, Alarm{AlarmCode::emergency_stop});
    raise_global(settings, AlarmCode::emergency_stop);
  }
  estop_ = inputs.estop;

  if (inputs.settings_lost) raise_global(settings, AlarmCode::settings_lost);

  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (drive_fault_[a]) raise(settings, axis_bit(a), Alarm{AlarmCode::drive_fault});

  comm_lost_ = inputs.communication_lost;
  if (comm_lost_ && any_motion()) {
    AxisMask moving = 0;
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      const AxisRun& run = axes_[a];
      const bool homing_phase = run.in_cycle && run.phase != Phase::waiting && run.phase != Phase::done;
      if (homing_phase || run.phase == Phase::jog || run.phase == Phase::move || run.motor.velocity_mm_per_s != 0)
        moving |= axis_bit(a);
    }
    raise(settings, moving, Alarm{AlarmCode::communication_lost});
  }

  permit_ = inputs.homing_permit;
  if (cycle_active_ && settings.global.permit_required && !permit_) {
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (axes_[a].in_cycle && axes_[a].phase != Phase::done) {
        raise(settings, axis_bit(a), Alarm{AlarmCode::permit_withdrawn});
        break;
      }
  }

  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    const AxisSettings& s = settings.axes[a];
    // A tripped shared limit stays "tripped" until its sensor releases: the
    // reset is taken and the jog away from it allowed without re-latching.
    if (limit_tripped_[a] && !run.sensor_active) limit_tripped_[a] = false;
    if (run.alarm || run.in_cycle || !run.homed) continue;
    const double pos = run.motor.position_mm + run.offset_mm;
    if (s.shared_limit && run.sensor_active && !limit_tripped_[a] &&
        sensor_channel(settings, a) == static_cast<int>(a)) {
      raise(settings, axis_bit(a), Alarm{AlarmCode::hard_limit, Phase::idle, AxisField::shared_limit, pos, 0});
      limit_tripped_[a] = true;
      continue;
    }
    const double tol = 1e-6;
    // Only moving further out is a fault: an axis left outside tightened
    // limits may still be jogged back in.
    const double v = run.motor.velocity_mm_per_s;
    if (s.soft_limits_enable && ((pos < s.soft_limit_min_mm - tol && v < 0) || (pos > s.soft_limit_max_mm + tol && v > 0)))
      raise(settings, axis_bit(a), Alarm{AlarmCode::soft_limit, Phase::idle, AxisField::none, pos, 0});
  }
}

CommandResult Engine::homing_refusal(const Settings& settings) const {
  if (estop_) return CommandResult::refused_estop;
  if (std::any_of(drive_fault_.begin(), drive_fault_.end(), [](bool f) { return f; }))
    return CommandResult::refused_drive_fault;
  if (any_alarm()) return CommandResult::refused_alarm;
  if (comm_lost_) return CommandResult::refused_communication_lost;
  if (settings.global.permit_required && !permit_) return CommandResult::refused_no_permit;
  if (any_motion()) return CommandResult::refused_busy;
  return CommandResult::accepted;
}

CommandResult Engine::motion_refusal(const Settings& settings, std::size_t axis) const {
  if (estop_) return CommandResult::refused_estop;
  if (any_alarm()) return CommandResult::refused_alarm;
  if (drive_fault_[axis]) return CommandResult::refused_drive_fault;
  if (comm_lost_) return CommandResult::refused_communication_lost;
  if (cycle_active_) return CommandResult::refused_busy;
  if (master_of(settings.axes[axis]) >= 0) return CommandResult::refused_slave_axis;
  // The same rule set as homing: an axis (or its gantry partner) whose
  // configuration is refused does not move at all.
  // Every axis linked to this one by slave_of, directly or through others.
  AxisMask group = axis_bit(axis);
  for (std::size_t pass = 0; pass < kAxisCount; ++pass)
    for (std::size_t s = 0; s < kAxisCount; ++s) {
      const int m = master_of(settings.axes[s]);
      if (m < 0 || m >= static_cast<int>(kAxisCount)) continue;
      if (group & (axis_bit(s) | axis_bit(static_cast<std::size_t>(m))))
        group |= axis_bit(s) | axis_bit(static_cast<std::size_t>(m));
    }
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((group & axis_bit(a)) && faults()[a]) return CommandResult::refused_settings_fault;
  const int partner = partner_of(settings, axis);
  if (limit_tripped_[axis] || (partner >= 0 && limit_tripped_[static_cast<std::size_t>(partner)]))
    return CommandResult::refused_hard_limit;
  return CommandResult::accepted;
}

// A jog is a motion command, except that an axis on a tripped shared limit
// may always jog away from its sensor (only away) until it releases.
CommandResult Engine::jog_refusal(const Settings& settings, std::size_t axis, std::int8_t dir) const {
  const CommandResult r = motion_refusal(settings, axis);
  if (r != CommandResult::refused_hard_limit) return r;
  const double toward = settings.axes[axis].direction == Direction::positive ? 1.0 : -1.0;
  return dir * toward < 0 ? CommandResult::accepted : CommandResult::refused_hard_limit;
}

void Engine::handle_commands(const Settings& settings, const Inputs& inputs) {
  const Commands& c = inputs.commands;
  if (c.reset_alarm) {
    ++command_count_;
    const bool fault = std::any_of(drive_fault_.begin(), drive_fault_.end(), [](bool f) { return f; });
    if (estop_ || fault || comm_lost_) {
      last_result_ = CommandResult::refused_cause_present;
    } else {
      clear_alarms();
      last_result_ = CommandResult::accepted;
    }
  }
  if (c.abort) {
    ++command_count_;
    // Abort during homing is an alarm on every axis still homing; abort of
    // a jog or move just stops it.
    if (cycle_active_) {
      AxisMask homing = 0;
      for (std::size_t a = 0; a < kAxisCount; ++a)
        if (axes_[a].in_cycle && axes_[a].phase != Phase::done) homing |= axis_bit(a);
      raise(settings, homing, Alarm{AlarmCode::aborted});
    }
    stop_all(settings);
    last_result_ = CommandResult::accepted;
  }

  // A physical input acts on a press seen after start-up, never on a level
  // held at power-up.
  const bool start_edge = !first_step_ && inputs.start_button && !prev_start_button_;
  prev_start_button_ = inputs.start_button;
  const bool home_all = c.home_all || start_edge;
  const AxisMask home_axes = c.home_axes & kAllAxes;
  if (home_all || home_axes) {
    ++command_count_;
    if (cycle_active_) {
      const bool same = home_all ? cycle_all_ : (!cycle_all_ && home_axes == cycle_requested_);
      last_result_ = same ? CommandResult::already_running : CommandResult::refused_busy;
    } else if (const CommandResult r = homing_refusal(settings); r != CommandResult::accepted) {
      last_result_ = r;
    } else {
      start_cycle(settings, home_all ? kAllAxes : home_axes, home_all);
    }
  }

  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const std::int8_t req = c.jog[a] > 0 ? 1 : (c.jog[a] < 0 ? -1 : 0);
    AxisRun& run = axes_[a];
    if (first_step_) {  // a jog held at power-up waits for its release and a new press
      prev_jog_request_[a] = req;
      continue;
    }
    if (req == 0) {
      if (run.phase == Phase::jog) run.set_phase(Phase::stopping);
    } else if (req != prev_jog_request_[a] || (run.phase != Phase::jog && run.phase != Phase::stopping)) {
      if (run.phase == Phase::jog && run.jog_dir() == req) {
        // still held
      } else if (req != prev_jog_request_[a]) {
        ++command_count_;
        CommandResult r = jog_refusal(settings, a, req);
        const bool homed = run.homed || settings.axes[a].mode == HomingMode::disabled;
        const int p = partner_of(settings, a);
        const bool recovering = limit_tripped_[a] || (p >= 0 && limit_tripped_[static_cast<std::size_t>(p)]);
        if (r == CommandResult::accepted && !homed && !recovering &&
            settings.global.allowed_without_homing == AllowedWithoutHoming::none)
          r = CommandResult::refused_not_homed;
        if (r == CommandResult::accepted && run.phase == Phase::move) r = CommandResult::refused_busy;
        last_result_ = r;
        if (r == CommandResult::accepted) {
          run.set_phase(Phase::jog);
          run.phase_data<phase_data::Jog>().dir = req;
          run.phase_start_mm = run.motor.position_mm;
        }
      }
    }
    prev_jog_request_[a] = req;
  }

  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(c.move_axes & axis_bit(a))) continue;
    ++command_count_;
    AxisRun& run = axes_[a];
    const AxisSettings& s = settings.axes[a];
    const double target = c.move_target_mm[a];
    CommandResult r = motion_refusal(settings, a);
    const bool homed = run.homed || s.mode == HomingMode::disabled;
    if (r == CommandResult::accepted && !std::isfinite(target)) r = CommandResult::refused_invalid;
    if (r == CommandResult::accepted && !homed &&
        settings.global.allowed_without_homing != AllowedWithoutHoming::all)
      r = CommandResult::refused_not_homed;
    if (r == CommandResult::accepted && homed && s.soft_limits_enable &&
        (target < s.soft_limit_min_mm || target > s.soft_limit_max_mm))
      r = CommandResult::refused_soft_limit;
    if (r == CommandResult::accepted && run.phase == Phase::jog) r = CommandResult::refused_busy;
    if (r == CommandResult::accepted && s.jog_feedrate_mm_per_min <= 0) r = CommandResult::refused_invalid;
    last_result_ = r;
    if (r == CommandResult::accepted) {
      run.set_phase(Phase::move);
      run.target_mm = target - run.offset_mm;
      run.phase_start_mm = run.motor.position_mm;
    }
  }
}

void Engine::start_cycle(const Settings& settings, AxisMask requested, bool all) {
  plan_ = plan_cycle(settings, requested, all);
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
  cycle_all_ = all;
  cycle_requested_ = requested;
  step_index_ = -1;
  last_result_ = CommandResult::accepted;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    if (!(covered & axis_bit(a))) continue;
    run.in_cycle = true;
    run.homed = false;
    run.set_phase(Phase::waiting);  // for its step
    run.entered = false;
    run.reached = Reached::nothing;
    run.aligning = false;
    run.follow_master = false;
  }
  for (std::size_t sl = 0; sl < kAxisCount; ++sl)
    if (const int m = gantry_master(settings, sl); m >= 0)
      pair_rel0_[sl] = axes_[sl].motor.position_mm - axes_[static_cast<std::size_t>(m)].motor.position_mm;
  start_step(settings);
}

bool Engine::start_step(const Settings& settings) {
  while (++step_index_ < static_cast<int>(plan_.steps.size())) {
    const AxisMask mask = plan_.steps[static_cast<std::size_t>(step_index_)];
    if (!mask) continue;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (mask & axis_bit(a)) begin_axis(settings, a);
    return true;
  }
  finish_cycle(settings);
  return false;
}

// An axis in no sequence step is given its coordinate where it stands (MASSO);
// an absolute axis always takes it from its encoder.
void Engine::assign_unsequenced(const Settings& settings, std::size_t a) {
  AxisRun& run = axes_[a];
  const AxisSettings& s = settings.axes[a];
  double machine_now = s.home_position_mm;
  if (mode_is_absolute(s.mode)) {
    if (!absolute_valid_[a]) return raise(settings, axis_bit(a), Alarm{AlarmCode::encoder_fault});
    machine_now = absolute_mm_[a] - s.home_position_mm;
  }
  const double new_offset = machine_now - run.motor.position_mm;
  run.home_correction_mm = new_offset - run.offset_mm;
  run.trigger_position_mm = run.motor.position_mm + run.offset_mm;
  run.offset_mm = new_offset;
  run.homed = true;
  run.set_phase(Phase::done);
}

void Engine::finish_cycle(const Settings& settings) {
  for (std::size_t a = 0; a < kAxisCount && cycle_active_; ++a)
    if (plan_.unsequenced & axis_bit(a)) assign_unsequenced(settings, a);
  if (!cycle_active_) return;  // an encoder fault ended the cycle
  for (AxisRun& run : axes_) run.in_cycle = false;
  cycle_active_ = false;
  step_index_ = -1;
  ++homing_cycles_;
}

void Engine::run_cycle(const Settings& settings) {
  if (!cycle_active_ || step_index_ < 0) return;
  const AxisMask mask = plan_.steps[static_cast<std::size_t>(step_index_)];
  for (std::size_t a = 0; a < kAxisCount && cycle_active_; ++a)
    if (mask & axis_bit(a)) run_axis(settings, a);
  if (!cycle_active_) return;
  bool all_done = true;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((mask & axis_bit(a)) && axes_[a].phase != Phase::done) all_done = false;
  if (all_done) start_step(settings);
}

void Engine::run_motion(const Settings& settings) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    const AxisSettings& s = settings.axes[a];
    const double accel = s.acceleration_mm_per_s2;
    const bool homed = run.homed || s.mode == HomingMode::disabled;
    switch (run.phase) {
      case Phase::jog: {
        double v = mm_per_min_to_mm_per_s(s.jog_feedrate_mm_per_min);
        if (!homed && settings.global.allowed_without_homing != AllowedWithoutHoming::all)
          v = std::min(v, mm_per_min_to_mm_per_s(100.0));
        if (homed && s.soft_limits_enable) {
          const double limit = (run.jog_dir() > 0 ? s.soft_limit_max_mm : s.soft_limit_min_mm) - run.offset_mm;
          const bool beyond = run.jog_dir() > 0 ? run.motor.position_mm >= limit : run.motor.position_mm <= limit;
          // At or past the limit in the jog's direction: hold still rather
          // than head back to the limit against the operator's direction.
          run.command = beyond ? stop_command(accel) : move_to_command(run.motor, limit, v, accel, last_dt_s_);
        } else {
          run.command = velocity_command(run.jog_dir() * v, accel);
        }
        break;
      }
      case Phase::move: {
        const double v = mm_per_min_to_mm_per_s(s.jog_feedrate_mm_per_min);
        run.command = move_to_command(run.motor, run.target_mm, v, accel, last_dt_s_);
        if (run.motor.position_mm == run.target_mm && run.motor.velocity_mm_per_s == 0) {
          run.set_phase(Phase::idle);
          run.command = stop_command(accel);
        }
        break;
      }
      case Phase::stopping:
        run.command = stop_command(accel);
        // A jog released while braking onto a soft limit: a late period can leave the
        // motor faster than the jog's braking planned, so keep the limit on the stop.
        if (homed && s.soft_limits_enable && run.motor.velocity_mm_per_s != 0) {
          run.command.has_limit = true;
          run.command.limit_mm =
              (run.motor.velocity_mm_per_s > 0 ? s.soft_limit_max_mm : s.soft_limit_min_mm) - run.offset_mm;
        }
        if (run.motor.velocity_mm_per_s == 0) run.set_phase(Phase::idle);
        break;
      case Phase::idle:
      case Phase::done:
        if (!run.in_cycle) run.command = stop_command(accel);
        break;
      default:
        break;
    }
  }
}

// A slave is locked to its master except while it homes on its own sensor.
void Engine::follow_masters(const Settings& settings) {
  for (std::size_t s = 0; s < kAxisCount; ++s) {
    const int m = gantry_master(settings, s);  // a refused pair is no pair: nothing follows
    if (m < 0) continue;
    AxisRun& slave = axes_[s];
    const AxisRun& master = axes_[static_cast<std::size_t>(m)];
    const bool independent = slave.in_cycle && !slave.follow_master;
    if (independent) continue;
    MotionCommand cmd = master.command;
    const double delta = slave.motor.position_mm - master.motor.position_mm;
    if (cmd.has_limit) cmd.limit_mm += delta;
    slave.command = cmd;
  }
}

// A gantry never racks beyond its slave's max_misalignment, stopping distance
// included, whatever the phase or the cause (a side on its sensor, a dead or
// stuck sensor, a squaring beyond the limit): each period, where both sides
// would come to rest if braked now, or after running this period's commands
// for up to two periods, is compared with their relative position at the
// start of the cycle. Before that could pass the limit, the pair is stopped
// with a misalignment alarm.
void Engine::guard_gantries(const Settings& settings) {
  for (std::size_t sl = 0; sl < kAxisCount; ++sl) {
    const int mi = gantry_master(settings, sl);
    if (mi < 0) continue;
    const std::size_t m = static_cast<std::size_t>(mi);
    AxisRun& slave = axes_[sl];
    const AxisRun& master = axes_[m];
    if (!slave.in_cycle && !master.in_cycle) continue;  // locked together outside a cycle
    const double limit = settings.axes[sl].max_misalignment_mm;
    auto rest = [&](const AxisRun& run, std::size_t axis, double h) {
      const MotionState at = integrate(run.motor, run.command, h);
      const double v = at.velocity_mm_per_s;
      const double d = stop_distance_mm(std::abs(v), settings.axes[axis].acceleration_mm_per_s2);
      return at.position_mm + (v > 0 ? d : (v < 0 ? -d : 0.0));
    };
    const double horizon = 2 * last_dt_s_;
    double worst = 0;
    for (int k = 0; k <= 4; ++k) {
      const double h = horizon * k / 4;
      const double dev = (rest(slave, sl, h) - rest(master, m, h)) - pair_rel0_[sl];
      worst = std::max(worst, std::abs(dev));
    }
    if (worst > limit) {
      raise(settings, axis_bit(sl), Alarm{AlarmCode::misalignment, slave.phase, AxisField::max_misalignment, worst, 0});
      follow_masters(settings);  // the slave brakes with the pair, not on its own old command
    }
  }
}

// The commutator output goes back to the master once the slave motor it was
// driving is at rest and no longer aligning.
void Engine::release_commutators(const Settings& settings) {
  for (std::size_t m = 0; m < kAxisCount; ++m) {
    AxisRun& master = axes_[m];
    if (!master.commutator_output) continue;
    const int sl = gantry_slave(settings, m);
    const AxisRun* slave = sl >= 0 ? &axes_[static_cast<std::size_t>(sl)] : nullptr;
    const bool busy = slave && slave->aligning && slave->in_cycle;
    const bool moving = slave && slave->motor.velocity_mm_per_s != 0;
    if (busy || moving) continue;
    master.commutator_output = false;
    filter_reset_[m] = true;
  }
}

void Engine::publish(const Settings& settings, const Inputs& inputs) {
  Status& st = status_;
  bool all_homed = true;
  bool moving = false;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisRun& run = axes_[a];
    const AxisSettings& s = settings.axes[a];
    AxisStatus& as = st.axes[a];
    as.phase = run.phase;
    as.alarm = run.alarm;
    as.position_mm = run.motor.position_mm + run.offset_mm;
    as.velocity_mm_per_s = run.motor.velocity_mm_per_s;
    as.homed = run.homed || s.mode == HomingMode::disabled;
    as.sensor = run.sensor_active;
    as.busy = run.in_cycle || run.phase == Phase::jog || run.phase == Phase::move ||
              run.phase == Phase::stopping || run.motor.velocity_mm_per_s != 0;
    as.trigger_position_mm = run.trigger_position_mm;
    as.home_correction_mm = run.home_correction_mm;
    as.stop_distance_mm =
        stop_distance_mm(mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min), s.acceleration_mm_per_s2);
    if (!std::isfinite(as.stop_distance_mm)) as.stop_distance_mm = 0;
    as.phase_distance_mm = std::abs(run.motor.position_mm - run.phase_start_mm);
    all_homed = all_homed && as.homed;
    moving = moving || (!run.in_cycle && as.busy);

    AxisOutputs& out = outputs_.axes[a];
    // An output channel's position is continuous: when the commutator hands
    // the master's output to the slave motor (and back), the channel goes on
    // from where it was, so a pulse generator never sees a jump.
    std::size_t source = a;
    if (run.commutator_output)
      if (const int sl = gantry_slave(settings, a); sl >= 0) source = static_cast<std::size_t>(sl);
    if (source != channel_source_[a]) {
      const double channel_mm = axes_[channel_source_[a]].motor.position_mm + channel_offset_[a];
      channel_offset_[a] = channel_mm - axes_[source].motor.position_mm;
      channel_source_[a] = source;
    }
    const AxisRun& src = axes_[source];
    out.motion = src.command;
    if (out.motion.has_limit) out.motion.limit_mm += channel_offset_[a];
    out.motor = src.motor;
    out.motor.position_mm += channel_offset_[a];
    out.enable = !estop_;
    out.push_output = run.push_output;
    out.commutator_output = run.commutator_output;
  }
  const bool alarm = any_alarm();
  st.alarm = alarm;
  st.homing = cycle_active_;
  st.estop = inputs.estop;
  st.global_alarm = global_alarm_;
  st.sequence_step = cycle_active_ && step_index_ >= 0 ? static_cast<std::uint8_t>(step_index_ + 1) : 0;
  st.homing_cycles = homing_cycles_;
  st.heartbeat = heartbeat_;
  st.last_command_result = last_result_;
  st.command_count = command_count_;
  if (alarm) st.state = MachineState::alarm;
  else if (cycle_active_) st.state = MachineState::homing;
  else if (moving) st.state = MachineState::moving;
  else if (all_homed) st.state = MachineState::homed;
  else st.state = MachineState::not_homed;

  std::uint16_t il = 0;
  if (estop_) il |= interlock::estop;
  if (std::any_of(drive_fault_.begin(), drive_fault_.end(), [](bool f) { return f; })) il |= interlock::drive_fault;
  if (alarm) il |= interlock::alarm_latched;
  if (global_alarm_ == AlarmCode::settings_lost) il |= interlock::settings_lost;
  if (comm_lost_) il |= interlock::communication_lost;
  if (settings.global.permit_required && !permit_) il |= interlock::permit_missing;
  if (!all_homed && settings.global.allowed_without_homing != AllowedWithoutHoming::all) il |= interlock::not_homed;
  if (cycle_active_) il |= interlock::homing_active;
  if (moving) il |= interlock::motion_active;
  st.interlocks = il;
  outputs_.homing_done_lamp = all_homed && !alarm;
}

}  // namespace homing
