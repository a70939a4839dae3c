#pragma once
// Latched alarms. Codes are register values (axis.<a>.alarm): never renumber.
#include <cstdint>
#include <iterator>
#include <span>
#include <string>
#include <string_view>

#include "enum_info.hpp"
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
  unlock_not_confirmed = 19,   // locking indexer: not unlocked within lock_timeout_ms
  lock_not_confirmed = 20,     // locking indexer: not locked again within lock_timeout_ms of rest
  lock_engaged = 21,           // locking indexer: reported locked while unlocked for motion
};
inline constexpr std::uint8_t kAlarmCodeCount = 22;

// The alarm table: per code its name, what happened (text) and what a
// maintenance technician checks (what_to_check). describe_alarm() says what
// happened with the axis and the figures, then what to check from here;
// hmi_maps/alarms.csv is this table.
struct AlarmInfo {
  AlarmCode value;
  std::string_view name;
  std::string_view text;
  std::string_view what_to_check;
};
inline constexpr AlarmInfo kAlarmInfo[] = {
    {AlarmCode::none, "none", "no alarm", ""},
    {AlarmCode::sensor_not_found, "sensor_not_found", "seek travelled max_seek_travel without a trigger",
     "check the home sensor and its wiring, its polarity (sensor_nc), the seek direction and max_seek_travel"},
    {AlarmCode::overrun_during_stop, "overrun_during_stop", "sensor released while stopping: trigger too short",
     "lengthen the trigger cam, lower seek_feedrate or raise acceleration"},
    {AlarmCode::stop_distance_exceeded, "stop_distance_exceeded", "came to rest further than max_stop_distance",
     "lower seek_feedrate or raise acceleration"},
    {AlarmCode::not_released, "not_released", "sensor still active after max_backoff",
     "check for a stuck or shorted sensor and its polarity (sensor_nc), or raise max_backoff; on a shared "
     "home/limit sensor after the pull-off, raise pull_off so the axis comes to rest off its sensor"},
    {AlarmCode::index_not_found, "index_not_found", "no index pulse within one index pitch",
     "check the index wiring and index_pitch"},
    {AlarmCode::slave_sensor_missing, "slave_sensor_missing", "a slave axis has no home sensor",
     "give the slave axis a switch mode and wire its own home sensor"},
    {AlarmCode::misalignment, "misalignment", "gantry misalignment beyond max_misalignment",
     "check both home sensors (a dead or stuck sensor, wiring, switch_compensation) and square the gantry "
     "mechanically"},
    {AlarmCode::hard_limit, "hard_limit", "shared home sensor tripped after homing",
     "jog the axis off the sensor after reset and re-home"},
    {AlarmCode::soft_limit, "soft_limit", "soft limit reached",
     "re-home the axis; if it recurs, check the mechanics and the drive for lost steps"},
    {AlarmCode::aborted, "aborted", "aborted by command", "reset and home again"},
    {AlarmCode::emergency_stop, "emergency_stop", "emergency stop", "release the e-stop, reset and home again"},
    {AlarmCode::drive_fault, "drive_fault", "drive fault", "check the drive's alarm display and power, then reset"},
    {AlarmCode::settings_fault, "settings_fault", "settings cannot work (see the message)",
     "correct the setting named (homingctl check lists every fault), then reset"},
    {AlarmCode::communication_lost, "communication_lost", "host watchdog expired",
     "check the PLC/HMI link and that the PLC changes host.heartbeat within global.watchdog_ms, then reset"},
    {AlarmCode::settings_lost, "settings_lost", "stored settings lost",
     "check every setting, then reset to allow homing; if it recurs, check the storage the settings "
     "database lives on"},
    {AlarmCode::reapproach_not_found, "reapproach_not_found", "re-approach travelled max_backoff without a trigger",
     "check the home sensor (a loose or flickering sensor), or raise max_backoff"},
    {AlarmCode::permit_withdrawn, "permit_withdrawn", "homing permit went off during a cycle",
     "close the guard / give the permit, reset and home again"},
    {AlarmCode::encoder_fault, "encoder_fault", "no valid absolute encoder position",
     "check the encoder cable, its power and the drive's encoder alarm, then reset and home again"},
    {AlarmCode::unlock_not_confirmed, "unlock_not_confirmed", "locking indexer did not report unlocked in time",
     "check the indexer's air or hydraulic supply, its unlock valve and the unlocked sensor and their wiring, "
     "or raise lock_timeout_ms; then reset"},
    {AlarmCode::lock_not_confirmed, "lock_not_confirmed", "locking indexer did not report locked in time after rest",
     "check that the locking pin can enter (the axis rests on an indexing position), the unlock valve drops "
     "and the unlocked sensor releases, or raise lock_timeout_ms; then reset"},
    {AlarmCode::lock_engaged, "lock_engaged", "locking indexer reported locked while unlocked for motion",
     "check the indexer's air or hydraulic pressure, the unlock valve and the unlocked sensor and its wiring "
     "(a flickering sensor), and the axis for damage; then reset and home again"},
};
static_assert(lists_every_value(kAlarmInfo, AlarmCode::lock_engaged));
static_assert(std::size(kAlarmInfo) == kAlarmCodeCount);
constexpr std::span<const AlarmInfo> enum_table(AlarmCode) { return kAlarmInfo; }

struct Alarm {
  AlarmCode code = AlarmCode::none;
  Phase phase = Phase::idle;        // phase the axis was in when it was raised
  AxisField field = AxisField::none;  // for settings faults: the setting at fault
  double value = 0;                 // a figure for the text (distance, limit...)
  std::uint8_t rule = 0;            // settings faults: the CheckRule broken
  explicit operator bool() const { return code != AlarmCode::none; }
};

std::string_view alarm_name(AlarmCode code);
// What a technician checks for this alarm ("" for none).
std::string_view alarm_what_to_check(AlarmCode code);

// A sentence a technician can act on, e.g.
// "X: home sensor not found within 200 mm of travel; check the sensor wiring and direction".
std::string describe_alarm(std::size_t axis, const Alarm& alarm, const Settings& settings);

}  // namespace homing
