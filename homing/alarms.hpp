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
  stop_not_found = 19,         // hard-stop homing travelled max_seek_travel without a stall
  stall_timeout = 20,          // hard-stop homing ran stall_timeout_ms without a stall
  stall_at_start = 21,         // hard-stop homing: the stall input was already active before moving
  drive_no_answer = 22,        // drive mode: no home done within drive_home_timeout
  drive_answered_at_once = 23, // drive mode: home done too soon after the request (the drive did not home)
  drive_reference_lost = 24,   // drive mode: home done went off while the axis was homed
  unlock_not_confirmed = 25,   // locking indexer: not unlocked within lock_timeout_ms
  lock_not_confirmed = 26,     // locking indexer: not locked again within lock_timeout_ms of rest
  lock_engaged = 27,           // locking indexer: reported locked while unlocked for motion
  cam_not_found = 28,          // home cam: both limit switches met without the cam
  limit_in_homing = 29,        // a limit switch met in a homing phase that must not reach one
  both_limits_active = 30,     // both limit switches active at once (wiring, polarity)
  limit_switch = 31,           // an end-of-travel limit switch tripped outside homing (hard limit)
  switch_not_repeatable = 32,  // the latch passes' spread exceeded max_latch_spread
  encoder_reversed = 33,       // hard-stop homing by following error: the encoder counted away from the stop
  travel_end_not_found = 34,   // measurement: no end of travel within max_seek_travel of the home
};
inline constexpr std::uint8_t kAlarmCodeCount = 35;

// The alarm table: per code its name, what happened (text) and what a
// maintenance technician checks (what_to_check). describe_alarm() says what
// happened with the axis and the figures, then what to check from here;
// hmi_maps/alarms.csv is this table.
// The unit of the figure an alarm quotes (axis.<a>.alarm_value): the axis's
// own (mm, deg on a rotary axis) unless its row says otherwise.
enum class AlarmValueUnit : std::uint8_t {
  axis,     // a distance or a position
  seconds,  // a time waited (the register's 0.001 is then ms)
  setting,  // the value of the setting the alarm names, in that setting's unit
};
struct AlarmInfo {
  AlarmCode value;
  std::string_view name;
  std::string_view text;
  std::string_view what_to_check;
  AlarmValueUnit value_unit = AlarmValueUnit::axis;
};
inline constexpr AlarmInfo kAlarmInfo[] = {
    {AlarmCode::none, "none", "no alarm", ""},
    {AlarmCode::sensor_not_found, "sensor_not_found", "seek travelled max_seek_travel without a trigger",
     "check the home sensor and its wiring, its polarity (sensor_nc), the seek direction and max_seek_travel"},
    {AlarmCode::overrun_during_stop, "overrun_during_stop", "sensor released while stopping: trigger too short",
     "lengthen the trigger cam, lower seek_feedrate or raise acceleration; a contact that bounces looks the same "
     "with debounce_ms 0: set debounce_ms (5-30 ms)"},
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
     "check the home sensor of the side named (axis.<a>.alarm_side: dead or stuck, wiring, polarity, "
     "switch_compensation); after the reset, home again: a cycle that starts racked squares the pair back, never "
     "further than max_misalignment from square; if it stops the same way again, square the gantry mechanically, "
     "then unhome it (cmd.unhome) so that the module forgets the old square"},
    {AlarmCode::hard_limit, "hard_limit", "shared home sensor tripped after homing",
     "jog the axis off the sensor after reset and re-home"},
    {AlarmCode::soft_limit, "soft_limit", "soft limit reached",
     "re-home the axis; if it recurs, check the mechanics and the drive for lost steps"},
    {AlarmCode::aborted, "aborted", "aborted by command", "reset and home again"},
    {AlarmCode::emergency_stop, "emergency_stop", "emergency stop", "release the e-stop, reset and home again"},
    {AlarmCode::drive_fault, "drive_fault", "drive fault", "check the drive's alarm display and power, then reset"},
    {AlarmCode::settings_fault, "settings_fault", "settings cannot work (see the message)",
     "correct the setting named (homingctl check lists every fault), then reset", AlarmValueUnit::setting},
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
    {AlarmCode::stop_not_found, "stop_not_found", "hard-stop homing travelled max_seek_travel without a stall",
     "check that the drive's stall output is wired and enabled (its torque limit and detection time), the "
     "homing direction, and that the mechanical stop lies within max_seek_travel; with stall_detect "
     "following_error, that max_following_error fits in the travel left beyond the stop"},
    {AlarmCode::stall_timeout, "stall_timeout", "hard-stop homing pushed for stall_timeout_ms without a stall",
     "check the drive's stall output and its detection time; raise stall_timeout_ms if the stop lies further "
     "than latch_feedrate covers in that time (with stall_detect following_error: plus max_following_error)", AlarmValueUnit::seconds},
    {AlarmCode::stall_at_start, "stall_at_start", "the stall input was active before the axis moved",
     "check the stall input's wiring and the drive (a stall output stuck on, or the drive still in torque "
     "limit); reset the drive, then home again"},
    {AlarmCode::drive_no_answer, "drive_no_answer", "the drive did not report home done within drive_home_timeout",
     "check the home request and home done wiring, that the drive's homing function is enabled and set up "
     "(its own home sensor, speeds), the drive's display, or raise drive_home_timeout_s", AlarmValueUnit::seconds},
    {AlarmCode::drive_answered_at_once, "drive_answered_at_once",
     "the drive reported home done at once: it did not home",
     "check that home done is the drive's home-end output (not ready or in-position), that it drops when a "
     "homing starts, and that the home request reaches the drive", AlarmValueUnit::seconds},
    {AlarmCode::drive_reference_lost, "drive_reference_lost", "the drive's home done went off while the axis was homed",
     "check the drive's alarm history and the home done wiring; the axis is no longer homed: reset and home again"},
    {AlarmCode::unlock_not_confirmed, "unlock_not_confirmed", "locking indexer did not report unlocked in time",
     "check the indexer's air or hydraulic supply, its unlock valve and the unlocked sensor and their wiring, "
     "or raise lock_timeout_ms; then reset"},
    {AlarmCode::lock_not_confirmed, "lock_not_confirmed", "locking indexer did not report locked in time after rest",
     "check that the locking pin can enter (the axis rests on an indexing position), the unlock valve drops "
     "and the unlocked sensor releases, or raise lock_timeout_ms; then reset"},
    {AlarmCode::lock_engaged, "lock_engaged", "locking indexer reported locked while unlocked for motion",
     "check the indexer's air or hydraulic pressure, the unlock valve and the unlocked sensor and its wiring "
     "(a flickering sensor), and the axis for damage; then reset and home again"},
    {AlarmCode::cam_not_found, "cam_not_found", "home cam not found between the limit switches",
     "check the home cam's sensor and its wiring and polarity (sensor_nc), and that the cam lies between "
     "the limit switches; then reset and home again"},
    {AlarmCode::limit_in_homing, "limit_in_homing", "a limit switch was met during a homing phase that must not reach one",
     "check that the home sensor or cam lies well inside the limit switches (max_backoff, pull_off and the final "
     "position must not reach a limit), that an axis sent back by return_to_start did not start next to one, and "
     "the limit switches' wiring; reset, jog off the limit switch and home again"},
    {AlarmCode::both_limits_active, "both_limits_active", "both limit switches read active at once",
     "check the limit switches' wiring (a broken wire on NC switches), their polarity (limits_nc) and supply; "
     "then reset"},
    {AlarmCode::limit_switch, "limit_switch", "end-of-travel limit switch tripped",
     "reset, jog the axis off the limit switch (only away from it is allowed) and find why it ran there "
     "(soft limits, lost steps, a move before homing); re-home if it was homed"},
    {AlarmCode::switch_not_repeatable, "switch_not_repeatable",
     "the latch passes found the reference edge further apart than max_latch_spread",
     "check the switch's mounting, the cam, and the latch feedrate"},
    {AlarmCode::encoder_reversed, "encoder_reversed",
     "hard-stop homing by following error: the encoder counted away from the stop while the motor pushed toward it",
     "check the encoder's counting direction (its A and B channels, the drive's encoder direction setting) and that "
     "it is this axis's encoder; nothing was homed"},
    {AlarmCode::travel_end_not_found, "travel_end_not_found",
     "measurement: no end of travel within max_seek_travel of the home",
     "check the opposite limit switch and its wiring and polarity (limits_nc), or on a hard-stop axis the drive's "
     "stall output; if the axis is longer than max_seek_travel, raise max_seek_travel for the measurement"},
};
static_assert(lists_every_value(kAlarmInfo, AlarmCode::travel_end_not_found));
static_assert(std::size(kAlarmInfo) == kAlarmCodeCount);
constexpr std::span<const AlarmInfo> enum_table(AlarmCode) { return kAlarmInfo; }

// A gantry's misalignment alarm: which side carried the pair out of square,
// and whether that side had found its home sensor (axis.<a>.alarm_side).
enum class GantrySide : std::uint8_t {
  none = 0,
  master_no_sensor = 1,   // the master ran on without finding its home sensor
  master_sensor_far = 2,  // the master found its home sensor too far from the slave's
  slave_no_sensor = 3,    // the slave ran on without finding its home sensor
  slave_sensor_far = 4,   // the slave found its home sensor too far from the master's
};
inline constexpr EnumInfo<GantrySide> kGantrySideInfo[] = {
    {GantrySide::none, "none", "not a gantry misalignment"},
    {GantrySide::master_no_sensor, "master_no_sensor", "the master did not find its home sensor"},
    {GantrySide::master_sensor_far, "master_sensor_far", "the master found its home sensor too far from the slave's"},
    {GantrySide::slave_no_sensor, "slave_no_sensor", "the slave did not find its home sensor"},
    {GantrySide::slave_sensor_far, "slave_sensor_far", "the slave found its home sensor too far from the master's"},
};
static_assert(lists_every_value(kGantrySideInfo, GantrySide::slave_sensor_far));
constexpr std::span<const EnumInfo<GantrySide>> enum_table(GantrySide) { return kGantrySideInfo; }
constexpr bool is_master_side(GantrySide s) {
  return s == GantrySide::master_no_sensor || s == GantrySide::master_sensor_far;
}

struct Alarm {
  AlarmCode code = AlarmCode::none;
  Phase phase = Phase::idle;        // phase the axis was in when it was raised
  AxisField field = AxisField::none;  // for settings faults: the setting at fault
  double value = 0;                 // a figure for the text (distance, limit...)
  std::uint8_t rule = 0;            // settings faults: the CheckRule broken; limit alarms: 1 negative, 2 positive limit
  // Misalignment: the side at fault, and how far out of square the cycle
  // found the pair (`value` is how far out of square it would have come).
  GantrySide side = GantrySide::none;
  double rack_at_start_mm = 0;
  explicit operator bool() const { return code != AlarmCode::none; }
};

std::string_view alarm_name(AlarmCode code);
// What a technician checks for this alarm ("" for none).
std::string_view alarm_what_to_check(AlarmCode code);
// The unit of axis.<a>.alarm_value for this alarm, as an HMI shows it:
// "axis" (mm, deg on a rotary axis), "s", or "setting" (the unit of the setting named).
std::string_view alarm_value_unit_name(AlarmCode code);

// A sentence a technician can act on, e.g.
// "X: home sensor not found within 200 mm of travel; check the sensor wiring and direction".
std::string describe_alarm(std::size_t axis, const Alarm& alarm, const Settings& settings);
// The same for an alarm not tied to one axis (status.global_alarm): no axis
// letter in front of it.
std::string describe_global_alarm(AlarmCode code, const Settings& settings);

}  // namespace homing
