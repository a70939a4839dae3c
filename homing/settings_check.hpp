#pragma once
// The configuration check run before any motion (and by the register layer on
// every settings write): refuses settings that cannot work, naming the setting.
#include <cstdint>
#include <optional>
#include <string>

#include "alarms.hpp"
#include "settings.hpp"

namespace homing {

enum class CheckRule : std::uint8_t {
  none = 0,
  not_positive,             // a feedrate, acceleration or travel that must be > 0
  latch_not_slower,         // latch feedrate must be below seek feedrate
  stop_distance_too_long,   // v²/2a + v·debounce beyond max_stop_distance
  negative,                 // a distance that must be >= 0
  missing_distance,         // pre-move, push or index pitch needed by the mode
  slave_invalid,            // slave_of names itself, a slave, or an axis that does not home
  slave_needs_sensor,       // a software-slaved axis must have its own home sensor
  commutator_needs_switch_master,
  soft_limits_inverted,
  outside_soft_limits,      // home or final position outside the enabled soft limits
};

struct SettingsFault {
  std::size_t axis = 0;
  AxisField field = AxisField::none;
  CheckRule rule = CheckRule::none;
  double value = 0;  // the figure that breaks the rule (e.g. the needed stop distance)
  AlarmCode code() const {
    return rule == CheckRule::slave_needs_sensor ? AlarmCode::slave_sensor_missing
                                                 : AlarmCode::settings_fault;
  }
};

// Checks one axis as it would home. The whole settings are needed for slaves.
std::optional<SettingsFault> check_axis(const Settings& settings, std::size_t axis);

// Stop distance of the seek, including the travel while the input is debounced.
double seek_stop_distance_mm(const AxisSettings& s);

std::string describe_fault(const SettingsFault& fault, const Settings& settings);

}  // namespace homing
