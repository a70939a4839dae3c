// The status of the period: per axis and for the machine, the state, the
// interlocks and the homing-done lamp.
#include <algorithm>
#include <cmath>

#include "engine.hpp"
#include "settings_check.hpp"

namespace homing {

void Engine::publish(const Settings& settings, const Inputs& inputs) {
  Status& st = status_;
  bool all_homed = true;
  bool limited = false;  // an unhomed axis that may not do everything yet
  bool moving = false;
  bool on_limit = false;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisRun& run = axes_[a];
    const AxisSettings& s = settings.axes[a];
    AxisStatus& as = st.axes[a];
    as.phase = run.shown_phase();
    as.alarm = run.alarm;
    as.position_mm = run.machine_position_mm();
    as.velocity_mm_per_s = run.motor.velocity_mm_per_s;
    as.homed = run.counts_as_homed(s.mode);
    as.sensor = inputs_[a].sensor_active;
    as.limit_min = run.readings.limit_min;
    as.limit_max = run.readings.limit_max;
    as.busy = run.busy();
    as.trigger_position_mm = run.trigger_position_mm;
    as.home_correction_mm = run.home_correction_mm;
    as.homed_at_cycle_start = run.homed_at_cycle_start;
    as.positions_set = run.positions_set;
    as.health = run.health;
    as.trust = run.trust();
    as.refcheck_error_mm = run.refcheck_error_mm;
    as.measurement = run.measurement;
    as.stop_distance_mm = seek_stop_distance_mm(s);  // the figure the configuration check holds to
    if (!std::isfinite(as.stop_distance_mm)) as.stop_distance_mm = 0;
    as.phase_distance_mm = std::abs(run.motor.position_mm - run.phase_start_mm);
    all_homed = all_homed && as.homed;
    limited = limited || (!as.homed && allowed_without_homing(settings, a) != AllowedWithoutHoming::all);
    moving = moving || (!run.in_cycle && as.busy);
    // A tripped shared home/limit sensor too, while the axis stands on it.
    on_limit = on_limit || as.limit_min || as.limit_max || run.limit_tripped;
  }
  const bool alarm = any_alarm();
  st.alarm = alarm;
  st.homing = cycle_active_;
  st.reference_check = cycle_active_ && cycle_is_check_;
  st.estop = inputs.estop;
  st.global_alarm = global_alarm_;
  st.first_alarm_axis = static_cast<std::int8_t>(first_alarm_axis_);
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
  if (any_drive_fault()) il |= interlock::drive_fault;
  if (alarm) il |= interlock::alarm_latched;
  if (global_alarm_ == AlarmCode::settings_lost) il |= interlock::settings_lost;
  if (heartbeat_stale_) il |= interlock::communication_lost;
  if (settings.global.permit_required && !permit_) il |= interlock::permit_missing;
  if (limited) il |= interlock::not_homed;
  if (cycle_active_) il |= interlock::homing_active;
  if (moving) il |= interlock::motion_active;
  if (on_limit) il |= interlock::limit_active;
  st.interlocks = il;
  outputs_.homing_done_lamp = all_homed && !alarm;
}

}  // namespace homing
