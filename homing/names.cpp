// Stable names of enum values: used in logs, exports and homingctl.
#include "alarms.hpp"
#include "phases.hpp"
#include "settings.hpp"
#include "status.hpp"

namespace homing {

std::string_view field_name(AxisField f) {
  switch (f) {
    case AxisField::none: return "";
    case AxisField::mode: return "mode";
    case AxisField::direction: return "direction";
    case AxisField::seek_feedrate: return "seek_feedrate";
    case AxisField::latch_feedrate: return "latch_feedrate";
    case AxisField::acceleration: return "acceleration";
    case AxisField::max_seek_travel: return "max_seek_travel";
    case AxisField::max_stop_distance: return "max_stop_distance";
    case AxisField::max_backoff: return "max_backoff";
    case AxisField::pull_off: return "pull_off";
    case AxisField::home_position: return "home_position";
    case AxisField::final_position: return "final_position";
    case AxisField::final_move_enable: return "final_move_enable";
    case AxisField::sensor_nc: return "sensor_nc";
    case AxisField::debounce_ms: return "debounce_ms";
    case AxisField::pre_move_mode: return "pre_move_mode";
    case AxisField::pre_move_distance: return "pre_move_distance";
    case AxisField::push_distance: return "push_distance";
    case AxisField::index_pitch: return "index_pitch";
    case AxisField::slave_of: return "slave_of";
    case AxisField::slave_mode: return "slave_mode";
    case AxisField::max_misalignment: return "max_misalignment";
    case AxisField::switch_compensation: return "switch_compensation";
    case AxisField::soft_limit_min: return "soft_limit_min";
    case AxisField::soft_limit_max: return "soft_limit_max";
    case AxisField::soft_limits_enable: return "soft_limits_enable";
    case AxisField::shared_limit: return "shared_limit";
    case AxisField::jog_feedrate: return "jog_feedrate";
  }
  return "?";
}

std::string_view mode_name(HomingMode m) {
  switch (m) {
    case HomingMode::disabled: return "disabled";
    case HomingMode::manual: return "manual";
    case HomingMode::switch_release: return "switch_release";
    case HomingMode::switch_reapproach: return "switch_reapproach";
    case HomingMode::switch_index: return "switch_index";
    case HomingMode::absolute: return "absolute";
    case HomingMode::absolute_final: return "absolute_final";
    case HomingMode::pushing_release: return "pushing_release";
    case HomingMode::pushing_reapproach: return "pushing_reapproach";
  }
  return "?";
}

std::string_view phase_name(Phase p) {
  switch (p) {
    case Phase::idle: return "idle";
    case Phase::waiting: return "waiting";
    case Phase::pre_move: return "pre_move";
    case Phase::seek: return "seek";
    case Phase::stop: return "stop";
    case Phase::push: return "push";
    case Phase::back_off: return "back_off";
    case Phase::reapproach: return "reapproach";
    case Phase::index: return "index";
    case Phase::pull_off: return "pull_off";
    case Phase::assign: return "assign";
    case Phase::final_move: return "final_move";
    case Phase::align_slave: return "align_slave";
    case Phase::done: return "done";
    case Phase::jog: return "jog";
    case Phase::move: return "move";
    case Phase::stopping: return "stopping";
  }
  return "?";
}

std::string_view alarm_name(AlarmCode c) {
  switch (c) {
    case AlarmCode::none: return "none";
    case AlarmCode::sensor_not_found: return "sensor_not_found";
    case AlarmCode::overrun_during_stop: return "overrun_during_stop";
    case AlarmCode::stop_distance_exceeded: return "stop_distance_exceeded";
    case AlarmCode::not_released: return "not_released";
    case AlarmCode::index_not_found: return "index_not_found";
    case AlarmCode::slave_sensor_missing: return "slave_sensor_missing";
    case AlarmCode::misalignment: return "misalignment";
    case AlarmCode::hard_limit: return "hard_limit";
    case AlarmCode::soft_limit: return "soft_limit";
    case AlarmCode::aborted: return "aborted";
    case AlarmCode::emergency_stop: return "emergency_stop";
    case AlarmCode::drive_fault: return "drive_fault";
    case AlarmCode::settings_fault: return "settings_fault";
    case AlarmCode::communication_lost: return "communication_lost";
    case AlarmCode::settings_lost: return "settings_lost";
    case AlarmCode::reapproach_not_found: return "reapproach_not_found";
    case AlarmCode::permit_withdrawn: return "permit_withdrawn";
    case AlarmCode::encoder_fault: return "encoder_fault";
  }
  return "?";
}

std::string_view state_name(MachineState s) {
  switch (s) {
    case MachineState::not_homed: return "not_homed";
    case MachineState::homing: return "homing";
    case MachineState::homed: return "homed";
    case MachineState::alarm: return "alarm";
    case MachineState::moving: return "moving";
  }
  return "?";
}

std::string_view command_result_name(CommandResult r) {
  switch (r) {
    case CommandResult::none: return "none";
    case CommandResult::accepted: return "accepted";
    case CommandResult::already_running: return "already_running";
    case CommandResult::refused_alarm: return "refused_alarm";
    case CommandResult::refused_estop: return "refused_estop";
    case CommandResult::refused_drive_fault: return "refused_drive_fault";
    case CommandResult::refused_busy: return "refused_busy";
    case CommandResult::refused_not_homed: return "refused_not_homed";
    case CommandResult::refused_no_permit: return "refused_no_permit";
    case CommandResult::refused_soft_limit: return "refused_soft_limit";
    case CommandResult::refused_slave_axis: return "refused_slave_axis";
    case CommandResult::refused_cause_present: return "refused_cause_present";
    case CommandResult::refused_invalid: return "refused_invalid";
    case CommandResult::refused_communication_lost: return "refused_communication_lost";
    case CommandResult::refused_settings_fault: return "refused_settings_fault";
    case CommandResult::refused_hard_limit: return "refused_hard_limit";
  }
  return "?";
}

std::string_view interlock_name(int bit) {
  switch (bit) {
    case 0: return "emergency stop pressed";
    case 1: return "drive fault";
    case 2: return "alarm latched (reset required)";
    case 3: return "settings lost (reset required)";
    case 4: return "communication lost (watchdog expired)";
    case 5: return "homing permit off";
    case 6: return "not homed (motion limited)";
    case 7: return "homing cycle running";
    case 8: return "jog or move running";
  }
  return "?";
}

}  // namespace homing
