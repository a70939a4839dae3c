#pragma once
// Latched alarms. Codes are register values (axis.<a>.alarm): never renumber.
#include <cstdint>
#include <string>
#include <string_view>

#include "phases.hpp"
#include "settings.hpp"

namespace homing {

enum class AlarmCode : std::uint8_t {
  none = 0,
  sensor_not_found = 1,        // seek travelled max_seek_travel without a trigger
  overrun_during_stop = 2,     // sensor released while stopping: trigger too short
  stop_distance_exceeded = 3,  // came to rest further than max_stop_distance from the trigger
  not_released = 4,            // back-off travelled max_backoff and the sensor stayed active
  index_not_found = 5,
  slave_sensor_missing = 6,
  misalignment = 7,
  hard_limit = 8,
  soft_limit = 9,
  aborted = 10,
  emergency_stop = 11,
  drive_fault = 12,
  settings_fault = 13,
  communication_lost = 14,
  settings_lost = 15,
  reapproach_not_found = 16,   // re-approach travelled max_backoff without a trigger
  permit_withdrawn = 17,       // homing permit went off during a cycle
  encoder_fault = 18,          // absolute mode without a valid encoder position
};
inline constexpr std::uint8_t kAlarmCodeCount = 19;

struct Alarm {
  AlarmCode code = AlarmCode::none;
  Phase phase = Phase::idle;        // phase the axis was in when it was raised
  AxisField field = AxisField::none;  // for settings faults: the setting at fault
  double value = 0;                 // a figure for the text (distance, limit...)
  std::uint8_t rule = 0;            // settings faults: the CheckRule broken
  explicit operator bool() const { return code != AlarmCode::none; }
};

std::string_view alarm_name(AlarmCode code);

// A sentence a technician can act on, e.g.
// "X: home sensor not found within 200 mm of travel; check the sensor wiring and direction".
std::string describe_alarm(std::size_t axis, const Alarm& alarm, const Settings& settings);

}  // namespace homing
