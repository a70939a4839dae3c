// Alarm texts: what happened, where, and what to check.
#include <fmt/format.h>

#include "alarms.hpp"
#include "gantry.hpp"
#include "settings_check.hpp"

namespace homing {

std::string describe_alarm(std::size_t axis, const Alarm& a, const Settings& settings) {
  // Figures from the settings the axis moves with (a slave its master's).
  const Settings moves = motion_settings(settings);
  const AxisSettings& s = moves.axes[axis];
  const char X = kAxisUpper[axis];
  const auto u = axis_unit(axis);
  const auto ph = phase_name(a.phase);
  switch (a.code) {
    case AlarmCode::none: return "";
    case AlarmCode::sensor_not_found:
      return fmt::format("{}: home sensor not found within {:g} {} of travel; check the sensor "
                         "wiring, its polarity (sensor_nc) and direction", X, s.max_seek_travel_mm, u);
    case AlarmCode::overrun_during_stop:
      return fmt::format("{}: home sensor released while stopping after the trigger; the trigger is "
                         "shorter than the stop distance ({:.3f} {}): lengthen the trigger cam, "
                         "lower seek_feedrate or raise acceleration", X, seek_stop_distance_mm(s), u);
    case AlarmCode::stop_distance_exceeded:
      return fmt::format("{}: came to rest {:.3f} {} past the trigger, more than max_stop_distance "
                         "{:g} {}; lower seek_feedrate or raise acceleration", X, a.value, u,
                         s.max_stop_distance_mm, u);
    case AlarmCode::not_released:
      if (a.phase == Phase::assign)
        return fmt::format("{}: shared home/limit sensor still active after the pull-off of {:g} {}; raise "
                           "pull_off so the axis comes to rest off its sensor", X, s.pull_off_mm, u);
      return fmt::format("{}: home sensor still active after backing off {:g} {} (phase {}); check "
                         "for a stuck or shorted sensor, sensor_nc, or raise max_backoff", X,
                         s.max_backoff_mm, u, ph);
    case AlarmCode::index_not_found:
      return fmt::format("{}: no encoder index pulse within {:.3f} {} after the switch edge; check the "
                         "index wiring and index_pitch", X, a.value, u);
    case AlarmCode::slave_sensor_missing:
      return fmt::format("{}: software-slaved axis has no home sensor of its own (mode {}); give it a "
                         "switch mode and wire its sensor", X, mode_name(s.mode));
    case AlarmCode::misalignment:
      return fmt::format("{}: gantry stopped during {} before racking by {:.3f} {}, more than "
                         "max_misalignment {:g} {}; check both home sensors (a dead or stuck sensor, "
                         "wiring, switch_compensation) and square the gantry mechanically", X, ph, a.value,
                         u, s.max_misalignment_mm, u);
    case AlarmCode::hard_limit:
      return fmt::format("{}: shared home/limit sensor tripped at {:.3f} {} after homing; jog the axis "
                         "off the sensor after reset and re-home", X, a.value, u);
    case AlarmCode::soft_limit:
      return fmt::format("{}: position {:.3f} {} beyond the soft limits [{:g}, {:g}]; re-home the axis",
                         X, a.value, u, s.soft_limit_min_mm, s.soft_limit_max_mm);
    case AlarmCode::aborted:
      return fmt::format("{}: homing aborted by command during {}; reset and home again", X, ph);
    case AlarmCode::emergency_stop:
      return fmt::format("{}: emergency stop during {}; release the e-stop, reset and home again", X, ph);
    case AlarmCode::drive_fault:
      return fmt::format("{}: drive fault during {}; check the drive's alarm display and power, then "
                         "reset", X, ph);
    case AlarmCode::settings_fault: {
      SettingsFault f{axis, a.field, static_cast<CheckRule>(a.rule), a.value};
      return fmt::format("{}: settings fault, homing refused before any motion: {}", X,
                         describe_fault(f, settings));
    }
    case AlarmCode::communication_lost:
      return fmt::format("{}: communication lost: host.heartbeat did not change for {} ms during {}; "
                         "check the PLC/HMI link, then reset", X, settings.global.watchdog_ms, ph);
    case AlarmCode::settings_lost:
      return fmt::format("settings lost: the settings database was unreadable and defaults were "
                         "loaded; check every setting, then reset to allow homing");
    case AlarmCode::reapproach_not_found:
      return fmt::format("{}: home sensor not found again within {:g} {} while re-approaching; check "
                         "the sensor and raise max_backoff", X, s.max_backoff_mm, u);
    case AlarmCode::permit_withdrawn:
      return fmt::format("{}: homing permit went off during {}; close the guard / give the permit, "
                         "reset and home again", X, ph);
    case AlarmCode::encoder_fault:
      return fmt::format("{}: absolute encoder gives no valid position; check the encoder link", X);
  }
  return "?";
}

}  // namespace homing
