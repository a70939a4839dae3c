// What raises an alarm from the inputs each period: e-stop, lost settings,
// drive faults, a drive's lost reference, the watchdog, the homing permit, and the hard and soft limits
// of a homed axis.
#include <bit>

#include "engine.hpp"
#include "mutation.hpp"

namespace homing {

void Engine::check_safety(const Settings& settings, const Inputs& inputs) {
  if (inputs.estop && !estop_) {
    AxisMask busy = 0, moving = 0;
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      const AxisRun& run = axes_[a];
      if (run.in_cycle || run.moving() || run.phase == Phase::jog || run.phase == Phase::move) busy |= axis_bit(a);
      const bool homing_phase = run.in_cycle && run.phase != Phase::waiting && run.phase != Phase::done;
      if (homing_phase || run.moving() || run.phase == Phase::jog || run.phase == Phase::move) moving |= axis_bit(a);
    }
    const bool first = first_alarm_axis_ < 0;
    raise(settings, busy, Alarm{AlarmCode::emergency_stop});
    raise_global(settings, AlarmCode::emergency_stop);
    // The axis shown as the machine's first (status.alarm_axis) is one the
    // e-stop stopped, not one waiting for its step of the sequence (as for an abort).
    if (first && moving) first_alarm_axis_ = static_cast<int>(std::countr_zero(static_cast<unsigned>(moving)));
  }
  estop_ = inputs.estop;

  if (inputs.settings_lost) raise_global(settings, AlarmCode::settings_lost);

  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!axes_[a].readings.drive_fault) continue;
    // A drive in fault does not follow its steps: an axis commanded to move
    // meanwhile is no longer where its coordinate says, whatever
    // global.alarm_clears_homed says (at rest it has lost nothing).
    if (axes_[a].moving() || axes_[a].period_start.velocity_mm_per_s != 0) axes_[a].lose_reference();
    if (planted(Mutant::drive_fault_as_sensor_alarm_elsewhere)) {
      raise(settings, axis_bit((a + 1) % kAxisCount), Alarm{AlarmCode::sensor_not_found});
      continue;
    }
    raise(settings, axis_bit(a), Alarm{AlarmCode::drive_fault});
  }

  check_drive_references(settings);
  check_limit_switches(settings);

  comm_lost_ = inputs.communication_lost;
  heartbeat_stale_ = inputs.heartbeat_stale || inputs.communication_lost;
  // A cycle at rest between two of its moves would start the next one: the
  // host that started it is gone, so the loss stops it as it stops motion.
  if (comm_lost_ && (any_motion() || cycle_active_)) {
    AxisMask moving = 0, cycle_left = 0;
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      const AxisRun& run = axes_[a];
      const bool homing_phase = run.in_cycle && run.phase != Phase::waiting && run.phase != Phase::done;
      if (homing_phase || run.phase == Phase::jog || run.phase == Phase::move || run.motor.velocity_mm_per_s != 0)
        moving |= axis_bit(a);
      if (run.in_cycle && run.phase != Phase::done) cycle_left |= axis_bit(a);
    }
    raise(settings, moving != 0 ? moving : cycle_left, Alarm{AlarmCode::communication_lost});
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
    const bool sensor_active = inputs_[a].sensor_active;
    if (run.limit_tripped && run.limit_side == 0 && !sensor_active) run.limit_tripped = false;
    const auto limits = s.soft_limits_enable ? std::optional(std::pair(s.soft_limit_min_mm, s.soft_limit_max_mm))
                                             : std::nullopt;
    const auto previous = run.soft_limits_seen;
    run.soft_limits_seen = limits;
    if (run.alarm || run.in_cycle || !run.homed()) {
      run.moved_limits_bound_mm.reset();
      continue;
    }
    const double pos = run.machine_position_mm();
    if (s.shared_limit && sensor_active && !run.limit_tripped && sensor_channel(settings, a) == static_cast<int>(a)) {
      raise(settings, axis_bit(a), Alarm{AlarmCode::hard_limit, Phase::idle, AxisField::shared_limit, pos, 0});
      run.limit_tripped = true;
      run.limit_side = 0;
      continue;
    }
    const double tol = 1e-6;
    // Only moving further out is a fault: an axis left outside tightened
    // limits may still be jogged back in.
    const double v = run.motor.velocity_mm_per_s;
    const auto outward_of = [&](const std::optional<std::pair<double, double>>& l) {
      return l && ((pos < l->first - tol && v < 0) || (pos > l->second + tol && v > 0));
    };
    // Limits tightened (or switched on) under its own jog or move, where it
    // can no longer stop inside them: the axis does not run past them, they
    // come to it. It brakes (run_motion) and only jogs back in from where it
    // rests; beyond where braking takes it, it is an overrun all the same. A
    // slave following its master, or an axis already out of the old limits,
    // is not excused.
    const bool own_motion = run.phase == Phase::jog || run.phase == Phase::move || run.phase == Phase::stopping;
    if (v == 0 || !own_motion) run.moved_limits_bound_mm.reset();
    if (limits != previous && limits && v != 0 && own_motion && !outward_of(previous)) {
      const double sign = v > 0 ? 1.0 : -1.0;
      const double stop_at =
          pos + sign * (stop_distance_mm(std::abs(v), s.acceleration_mm_per_s2) + std::abs(v) * last_dt_s_ + 1e-3);
      if (v > 0 ? stop_at > limits->second : stop_at < limits->first) run.moved_limits_bound_mm = stop_at;
    }
    const bool excused =
        run.moved_limits_bound_mm && (v > 0 ? pos <= *run.moved_limits_bound_mm : pos >= *run.moved_limits_bound_mm);
    if (outward_of(limits) && !excused)
      raise(settings, axis_bit(a), Alarm{AlarmCode::soft_limit, Phase::idle, AxisField::none, pos, 0});
  }
}

// An axis homed by its drive rests its coordinate on the drive's reference:
// when the drive's home done goes off (the drive lost it, or the wire broke)
// the axis is no longer homed, whatever global.alarm_clears_homed says.
void Engine::check_drive_references(const Settings& settings) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    if (!run.drive_referenced) continue;
    if (!mode_row(settings.axes[a].mode).runs(Phase::drive_homing)) {
      run.drive_referenced = false;
      continue;
    }
    if (run.readings.drive_done || !run.homed() || run.phase == Phase::drive_homing) continue;
    const double pos = run.machine_position_mm();
    run.home.reset();
    run.drive_referenced = false;
    raise(settings, axis_bit(a), Alarm{AlarmCode::drive_reference_lost, Phase::idle, AxisField::none, pos, 0});
  }
}

}  // namespace homing
