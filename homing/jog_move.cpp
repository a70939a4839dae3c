// Jog and move: when they are refused, how they start, and how each runs
// and stops within the soft limits. An axis on a tripped shared limit may
// still be jogged away from its sensor (hard-limit recovery).
#include <algorithm>
#include <cmath>

#include "engine.hpp"
#include "gantry.hpp"

namespace homing {
namespace {

// At (within a micrometre) or beyond the soft limit a jog in dir heads for:
// where a jog held toward it ends.
bool at_soft_limit(const AxisSettings& s, const AxisRun& run, std::int8_t dir) {
  constexpr double kAtLimitMm = 1e-6;
  const double at = run.machine_position_mm();
  return dir > 0 ? at >= s.soft_limit_max_mm - kAtLimitMm : at <= s.soft_limit_min_mm + kAtLimitMm;
}

}  // namespace

// The axis and its gantry partner move together: a limit switch of either
// counts for both.
template <typename Pred>
bool Engine::any_of_pair(const Settings& settings, std::size_t axis, Pred pred) const {
  const int partner = gantry_partner(settings, axis);
  for (const int a : {static_cast<int>(axis), partner}) {
    if (a < 0) continue;
    const auto i = static_cast<std::size_t>(a);
    if (settings.axes[i].limits_fitted && pred(axes_[i].readings)) return true;
  }
  return false;
}

// Both ends at once cannot be (limit_switches.cpp): no direction is away
// from them, and the technician is told to look at the wiring instead.
bool Engine::on_both_limits(const Settings& settings, std::size_t axis) const {
  return any_of_pair(settings, axis, [](const AxisReadings& in) { return in.limit_min && in.limit_max; });
}

bool Engine::limit_ahead(const Settings& settings, std::size_t axis, double toward) const {
  return any_of_pair(settings, axis, [toward](const AxisReadings& in) { return in.limit_toward(toward); });
}

bool Engine::on_limit_switch(const Settings& settings, std::size_t axis) const {
  return any_of_pair(settings, axis, [](const AxisReadings& in) { return in.limit_min || in.limit_max; });
}

CommandResult Engine::motion_refusal(const Settings& settings, std::size_t axis) const {
  if (estop_) return CommandResult::refused_estop;
  if (any_alarm()) return CommandResult::refused_alarm;
  if (axes_[axis].readings.drive_fault) return CommandResult::refused_drive_fault;
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
  // A disabled axis is no axis of this machine (homing-methods.md: never moves);
  // one named in a gantry is the settings fault above, which says more.
  if (settings.axes[axis].mode == HomingMode::disabled) return CommandResult::refused_invalid;
  const int partner = gantry_partner(settings, axis);
  if (axes_[axis].limit_tripped || (partner >= 0 && axes_[static_cast<std::size_t>(partner)].limit_tripped))
    return CommandResult::refused_hard_limit;
  return CommandResult::accepted;
}

// A jog is a motion command, except that an axis on a tripped shared limit
// may always jog away from its sensor (only away) until it releases.
// Limit switches: a jog into an active one is refused, tripped or not.
CommandResult Engine::jog_refusal(const Settings& settings, std::size_t axis, std::int8_t dir) const {
  const CommandResult r = motion_refusal(settings, axis);
  if ((r == CommandResult::accepted || r == CommandResult::refused_hard_limit) && on_both_limits(settings, axis))
    return CommandResult::refused_both_limits;
  if (r == CommandResult::accepted && limit_ahead(settings, axis, dir)) return CommandResult::refused_hard_limit;
  if (r != CommandResult::refused_hard_limit) return r;
  // Every tripped limit of the axis and its gantry partner must lie behind the
  // jog: a limit switch at its own end, a shared home sensor toward direction.
  const double seek_toward = settings.axes[axis].direction == Direction::positive ? 1.0 : -1.0;
  const int partner = gantry_partner(settings, axis);
  for (const int a : {static_cast<int>(axis), partner}) {
    if (a < 0) continue;
    const AxisRun& t = axes_[static_cast<std::size_t>(a)];
    if (!t.limit_tripped) continue;
    const double toward = t.limit_side != 0 ? static_cast<double>(t.limit_side) : seek_toward;
    if (dir * toward >= 0) return CommandResult::refused_hard_limit;
  }
  if (limit_ahead(settings, axis, dir)) return CommandResult::refused_hard_limit;
  return CommandResult::accepted;
}

// A jog is a level: it starts on a press (a change of the request), runs
// while held and stops on release. On a tripped shared limit it may only
// run away from the sensor, whether homed or not (hard-limit recovery).
void Engine::jog_commands(const Settings& settings, const Commands& c) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const std::int8_t req = c.jog[a] > 0 ? 1 : (c.jog[a] < 0 ? -1 : 0);
    AxisRun& run = axes_[a];
    if (first_step_) {  // a jog held at power-up waits for its release and a new press
      run.prev_jog_request = req;
      continue;
    }
    if (req == 0) {
      if (run.phase == Phase::jog) run.set_phase(Phase::stopping);
    } else if (req != run.prev_jog_request || (run.phase != Phase::jog && run.phase != Phase::stopping)) {
      if (run.phase == Phase::jog && run.jog_dir() == req) {
        // still held
      } else if (req != run.prev_jog_request) {
        ++command_count_;
        CommandResult r = jog_refusal(settings, a, req);
        const bool homed = run.counts_as_homed(settings.axes[a].mode);
        const int p = gantry_partner(settings, a);
        // Off a tripped limit, or off an active limit switch it (or its gantry
        // partner) stands on (powered up there: jog_refusal has refused a jog toward it).
        const bool recovering = run.limit_tripped || on_limit_switch(settings, a) ||
                                (p >= 0 && axes_[static_cast<std::size_t>(p)].limit_tripped);
        if (r == CommandResult::accepted && !homed && !recovering &&
            allowed_without_homing(settings, a) == AllowedWithoutHoming::none)
          r = CommandResult::refused_not_homed;
        // A jog toward the soft limit it stands at would not move: refused, as a move there is.
        if (r == CommandResult::accepted && homed && settings.axes[a].soft_limits_enable &&
            at_soft_limit(settings.axes[a], run, req))
          r = CommandResult::refused_soft_limit;
        if (r == CommandResult::accepted && run.phase == Phase::move) r = CommandResult::refused_busy;
        last_result_ = r;
        if (r == CommandResult::accepted) {
          run.set_phase(Phase::jog);
          run.phase_data<phase_data::Jog>().dir = req;
          run.phase_start_mm = run.motor.position_mm;
        }
      }
    }
    run.prev_jog_request = req;
  }
}

void Engine::move_commands(const Settings& settings, const Commands& c) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(c.move_axes & axis_bit(a))) continue;
    ++command_count_;
    AxisRun& run = axes_[a];
    const AxisSettings& s = settings.axes[a];
    const double target = c.move_target_mm[a];
    CommandResult r = motion_refusal(settings, a);
    const bool homed = run.counts_as_homed(s.mode);
    if ((r == CommandResult::accepted || r == CommandResult::refused_hard_limit) && on_both_limits(settings, a))
      r = CommandResult::refused_both_limits;
    if (r == CommandResult::accepted && !std::isfinite(target)) r = CommandResult::refused_invalid;
    if (r == CommandResult::accepted && !homed &&
        allowed_without_homing(settings, a) != AllowedWithoutHoming::all)
      r = CommandResult::refused_not_homed;
    if (r == CommandResult::accepted && homed && s.soft_limits_enable &&
        (target < s.soft_limit_min_mm || target > s.soft_limit_max_mm))
      r = CommandResult::refused_soft_limit;
    // A move toward an active limit switch (its own or its gantry partner's) would trip it at once.
    if (r == CommandResult::accepted && std::isfinite(target) &&
        target != run.machine_position_mm() && limit_ahead(settings, a, target - run.machine_position_mm()))
      r = CommandResult::refused_hard_limit;
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

void Engine::run_motion(const Settings& settings) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    const AxisSettings& s = settings.axes[a];
    const double accel = s.acceleration_mm_per_s2;
    const bool homed = run.counts_as_homed(s.mode);
    switch (run.phase) {
      case Phase::jog: {
        double v = mm_per_min_to_mm_per_s(s.jog_feedrate_mm_per_min);
        if (!homed && allowed_without_homing(settings, a) != AllowedWithoutHoming::all)
          v = std::min(v, mm_per_min_to_mm_per_s(100.0));
        if (homed && s.soft_limits_enable) {
          const double limit = (run.jog_dir() > 0 ? s.soft_limit_max_mm : s.soft_limit_min_mm) - run.offset_mm;
          const bool beyond = run.jog_dir() > 0 ? run.motor.position_mm >= limit : run.motor.position_mm <= limit;
          // At or past the limit in the jog's direction: stop rather than
          // head back to the limit against the operator's direction; at rest
          // there the jog has ended (the axis no longer reads moving), and a
          // new press toward the limit is refused_soft_limit.
          run.command = beyond ? stop_command(accel) : move_to_command(run.motor, limit, v, accel, last_dt_s_);
          if (beyond && run.motor.velocity_mm_per_s == 0) run.set_phase(Phase::idle);
        } else {
          run.command = velocity_command(run.jog_dir() * v, accel);
        }
        break;
      }
      case Phase::move: {
        const double vel = run.motor.velocity_mm_per_s;
        const bool heading_out = (vel > 0 && run.target_mm > run.motor.position_mm) ||
                                 (vel < 0 && run.target_mm < run.motor.position_mm);
        if (run.moved_limits_bound_mm && heading_out) {  // soft limits tightened past its stop: brake, as a jog does
          run.set_phase(Phase::stopping);
          run.command = stop_command(accel);
          break;
        }
        // Limits tightened ahead of the target since the move began: it ends at the limit.
        if (homed && s.soft_limits_enable)
          run.target_mm = std::clamp(run.target_mm, s.soft_limit_min_mm - run.offset_mm, s.soft_limit_max_mm - run.offset_mm);
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
        if (homed && s.soft_limits_enable && run.motor.velocity_mm_per_s != 0 && !run.moved_limits_bound_mm) {
          run.command.has_limit = true;
          run.command.limit_mm =
              (run.motor.velocity_mm_per_s > 0 ? s.soft_limit_max_mm : s.soft_limit_min_mm) - run.offset_mm;
        }
        if (run.motor.velocity_mm_per_s == 0) {
          run.set_phase(Phase::idle);
          run.push_output = false;  // a push cut short: at rest, full current again
        }
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

}  // namespace homing
