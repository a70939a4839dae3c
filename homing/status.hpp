#pragma once
// What the engine reports each period. Enum values are register values.
#include <array>
#include <cstdint>
#include <iterator>
#include <span>
#include <string_view>

#include "alarms.hpp"
#include "axes.hpp"
#include "enum_info.hpp"
#include "health.hpp"
#include "measure.hpp"
#include "phases.hpp"
#include "trust.hpp"

namespace homing {

enum class MachineState : std::uint8_t { not_homed = 0, homing = 1, homed = 2, alarm = 3, moving = 4 };
inline constexpr EnumInfo<MachineState> kMachineStateInfo[] = {
    {MachineState::not_homed, "not_homed", "not homed"},
    {MachineState::homing, "homing", "a homing cycle runs"},
    {MachineState::homed, "homed", "all homing axes are homed"},
    {MachineState::alarm, "alarm", "an alarm is latched; reset it"},
    {MachineState::moving, "moving", "a jog or move runs"},
};
static_assert(lists_every_value(kMachineStateInfo, MachineState::moving));
constexpr std::span<const EnumInfo<MachineState>> enum_table(MachineState) { return kMachineStateInfo; }

enum class CommandResult : std::uint8_t {
  none = 0,
  accepted = 1,
  already_running = 2,       // the same command is still running; not restarted
  refused_alarm = 3,         // an alarm is latched: reset first
  refused_estop = 4,
  refused_drive_fault = 5,
  refused_busy = 6,          // another homing cycle or motion is running
  refused_not_homed = 7,     // not allowed before homing (global.allowed_without_homing)
  refused_no_permit = 8,     // global.permit_required and the permit is off
  refused_soft_limit = 9,    // target outside the soft limits, or a jog toward the soft limit it stands at
  refused_slave_axis = 10,   // a slave axis is commanded through its master
  refused_cause_present = 11,  // reset refused: e-stop, drive fault or watchdog still active
  refused_invalid = 12,      // the command itself makes no sense (bad axis, bad target)
  refused_communication_lost = 13,
  refused_settings_fault = 14,  // the configuration check refused the cycle: see the axis alarm
  refused_hard_limit = 15,   // on a tripped limit or toward an active limit switch: only a jog away is allowed
  refused_home_all_only = 16,  // global.single_axis_homing is off: the machine homes all axes or none
  refused_homed = 17,        // set position: the axis is homed; its coordinate comes from its reference
  refused_no_switch_edge = 18,  // reference check: the axis's method has no switch edge to check
  refused_no_clean_stop = 19,   // reference check: axis.<a>.trust is not last_stop_clean
  refused_gantry_pair = 20,     // reference check: a gantry pair is squared by a full cycle only
  refused_no_travel_end = 21,   // measurement: the axis homes at no end of travel, or cannot tell the opposite end
  cancelled_by_abort = 22,      // a start that came with an abort (one request, or one period): abort wins
  refused_both_limits = 23,     // jog or move: both limit switches of the axis or its partner read active (wiring, limits_nc)
};
inline constexpr std::uint8_t kCommandResultCount = 24;
inline constexpr EnumInfo<CommandResult> kCommandResultInfo[] = {
    {CommandResult::none, "none", "no command yet"},
    {CommandResult::accepted, "accepted", "the last command started"},
    {CommandResult::already_running, "already_running", "the same command is still running; not restarted"},
    {CommandResult::refused_alarm, "refused_alarm", "an alarm is latched: reset first"},
    {CommandResult::refused_estop, "refused_estop", "the emergency stop is pressed: release it, then reset"},
    {CommandResult::refused_drive_fault, "refused_drive_fault", "a drive reports a fault: check the drive, then reset"},
    {CommandResult::refused_busy, "refused_busy", "another homing cycle or motion is running (abort stops it)"},
    {CommandResult::refused_not_homed, "refused_not_homed",
     "not allowed before homing (global.allowed_without_homing): home first"},
    {CommandResult::refused_no_permit, "refused_no_permit",
     "global.permit_required is on and the homing permit (host.homing_permit or the permit input) is off"},
    {CommandResult::refused_soft_limit, "refused_soft_limit", "target outside the soft limits, or a jog toward the soft limit it stands at"},
    {CommandResult::refused_slave_axis, "refused_slave_axis", "this axis is a gantry slave: command its master"},
    {CommandResult::refused_cause_present, "refused_cause_present",
     "the cause (e-stop, drive fault or watchdog) is still present: remove it, then reset"},
    {CommandResult::refused_invalid, "refused_invalid", "the command makes no sense here (axis disabled or bad target)"},
    {CommandResult::refused_communication_lost, "refused_communication_lost",
     "the watchdog expired: host.heartbeat stopped changing; write it again (and reset the alarm if one latched)"},
    {CommandResult::refused_settings_fault, "refused_settings_fault",
     "the configuration check refused the command: see the axis alarm or homingctl check"},
    {CommandResult::refused_hard_limit, "refused_hard_limit",
     "on a tripped limit (an end-of-travel limit switch, or a home sensor shared as a limit) or toward an active "
     "limit switch: only a jog away from it is allowed until it releases"},
    {CommandResult::refused_home_all_only, "refused_home_all_only",
     "global.single_axis_homing is off: this machine homes all axes together (cmd.home_all), never one alone"},
    {CommandResult::refused_homed, "refused_homed",
     "the axis is homed: its coordinate comes from its reference; unhome it first (cmd.unhome.<a>) to set it by hand"},
    {CommandResult::refused_no_switch_edge, "refused_no_switch_edge",
     "reference check refused: the axis's homing method has no switch edge to check (manual, absolute, hard stop, "
     "drive, switch + index, pushing): home it with a full cycle"},
    {CommandResult::refused_no_clean_stop, "refused_no_clean_stop",
     "reference check refused: axis.<a>.trust is not last_stop_clean (its last stop was not clean, its home "
     "settings changed, a check already failed, or it is homed): home it with a full cycle"},
    {CommandResult::refused_gantry_pair, "refused_gantry_pair",
     "reference check or measurement refused: the axis is one side of a gantry pair, which only a full cycle squares"},
    {CommandResult::refused_no_travel_end, "refused_no_travel_end",
     "measurement refused: it needs both a homing method that homes at one end of the travel (a switch, pushing "
     "or a hard stop; not a home cam, manual, absolute or drive) and something that tells the opposite end "
     "(limit switches: limits_fitted = 1; or a hard stop with stall_detect = stall_input)"},
    {CommandResult::cancelled_by_abort, "cancelled_by_abort",
     "not started: an abort came with it (in the same request or within the same control period) and abort wins; "
     "send the start again once the abort is done"},
    {CommandResult::refused_both_limits, "refused_both_limits",
     "both limit switches of the axis (or of its gantry partner) read active at once, so no direction is away "
     "from them: a broken wire to normally-closed switches or a wrong limits_nc; check the wiring and "
     "axis.<a>.limits_nc of the axis whose axis.<a>.limit_min and limit_max both read 1; nothing jogs or moves "
     "until one reads released"},
};
static_assert(lists_every_value(kCommandResultInfo, CommandResult::refused_both_limits));
static_assert(std::size(kCommandResultInfo) == kCommandResultCount);
constexpr std::span<const EnumInfo<CommandResult>> enum_table(CommandResult) { return kCommandResultInfo; }

// status.interlocks: what blocks homing or motion now; 0 = free to move.
namespace interlock {
inline constexpr std::uint16_t estop = 1u << 0;
inline constexpr std::uint16_t drive_fault = 1u << 1;
inline constexpr std::uint16_t alarm_latched = 1u << 2;
inline constexpr std::uint16_t settings_lost = 1u << 3;
inline constexpr std::uint16_t communication_lost = 1u << 4;
inline constexpr std::uint16_t permit_missing = 1u << 5;
inline constexpr std::uint16_t not_homed = 1u << 6;       // motion limited until homed
inline constexpr std::uint16_t homing_active = 1u << 7;
inline constexpr std::uint16_t motion_active = 1u << 8;   // jog or move running
inline constexpr std::uint16_t limit_active = 1u << 9;    // an axis stands on a limit switch: no jog or move toward it
inline constexpr int kCount = 10;

// Per bit: its name (register bit name) and text (what homingctl and HMIs show).
struct BitInfo {
  int bit;
  std::uint16_t mask;
  std::string_view name;
  std::string_view text;
};
inline constexpr BitInfo kInfo[] = {
    {0, estop, "estop", "emergency stop pressed"},
    {1, drive_fault, "drive_fault", "drive fault"},
    {2, alarm_latched, "alarm_latched", "alarm latched (reset required)"},
    {3, settings_lost, "settings_lost", "settings lost (reset required)"},
    {4, communication_lost, "communication_lost", "communication lost (watchdog expired)"},
    {5, permit_missing, "permit_missing", "homing permit off"},
    {6, not_homed, "not_homed", "not homed (motion limited)"},
    {7, homing_active, "homing_active", "homing cycle running"},
    {8, motion_active, "motion_active", "jog or move running"},
    {9, limit_active, "limit_active", "limit switch active (axis.<a>.limit_min/max): jog away from it"},
};
constexpr bool bits_in_order() {
  for (int i = 0; i < kCount; ++i)
    if (kInfo[i].bit != i || kInfo[i].mask != 1u << i) return false;
  return std::size(kInfo) == static_cast<std::size_t>(kCount);
}
static_assert(bits_in_order());
}  // namespace interlock

// Whether a homing command may start now, judged by what blocks it (the
// status.interlocks bits): estop, drive fault, a latched alarm, a lost link,
// a missing permit, then a cycle or motion already running (refused_busy).
// The engine judges every home command with it, and the runtime answers a
// cmd.home_axes write with it before anything of the write is applied.
CommandResult homing_refusal_of(std::uint16_t interlocks);
// Whether cmd.reset_alarm is refused for a cause still present (e-stop,
// drive fault, a stale heartbeat), judged by the same bits. The engine also
// refuses it while a failed cycle winds down (refused_busy), which no
// interlock bit shows.
CommandResult reset_refusal_of(std::uint16_t interlocks);

std::string_view state_name(MachineState s);
std::string_view command_result_name(CommandResult r);
std::string_view interlock_name(int bit);  // the bit's text ("emergency stop pressed")

struct AxisStatus {
  Phase phase = Phase::idle;
  Alarm alarm{};
  double position_mm = 0;           // machine coordinates
  double velocity_mm_per_s = 0;
  bool homed = false;
  bool sensor = false;              // home sensor active (debounced, polarity applied)
  bool limit_min = false;           // the negative end's limit switch active (limits_fitted, polarity applied)
  bool limit_max = false;           // the positive end's
  bool busy = false;
  double trigger_position_mm = 0;   // reference edge, in the coordinates believed before assign
  double home_correction_mm = 0;    // assigned - believed at the reference edge
  // The axis was homed (and still trusted) when its last homing cycle
  // started: only then does home_correction measure drift (lost steps, a
  // sensor that moved). Otherwise it only says where the axis happened to stand.
  bool homed_at_cycle_start = false;
  double stop_distance_mm = 0;      // v²/2a of the seek
  double phase_distance_mm = 0;     // travelled in the current phase
  SwitchHealth health{};            // what the last homing cycle measured of the switch (health.hpp)
  // Set-position commands carried out on this axis since start: the runtime
  // audits each one (who set which coordinate).
  std::uint32_t positions_set = 0;
  Trust trust = Trust::unknown;     // how far position_mm can be believed (trust.hpp)
  // The last reference check: where it found the switch edge less where the
  // stored position put it (the figure it was accepted or refused on).
  double refcheck_error_mm = 0;
  // The last measurement (cmd.measure.<a>; measure.hpp), all 0 until one
  // found its end: usable travel from the home position, and the settings it suggests.
  Measurement measurement{};
};

struct Status {
  MachineState state = MachineState::not_homed;
  std::uint8_t sequence_step = 0;  // 1..6 while homing, 0 otherwise
  std::uint32_t homing_cycles = 0;  // cycles completed successfully
  std::uint32_t heartbeat = 0;      // control periods since start
  CommandResult last_command_result = CommandResult::none;
  std::uint32_t command_count = 0;  // commands judged so far: last_command_result belongs to the latest
  std::uint16_t interlocks = 0;
  AlarmCode global_alarm = AlarmCode::none;  // alarm not tied to one axis (e-stop at rest, settings lost)
  // The axis that latched the first alarm since the last reset (-1: none or
  // not known): later alarms on other axes, while a failure policy winds a
  // cycle down or the axes brake, never take its place (status.alarm_axis).
  std::int8_t first_alarm_axis = -1;
  bool alarm = false;
  bool homing = false;
  bool estop = false;
  bool reference_check = false;     // the running cycle (homing) is a reference check, not a homing cycle
  std::array<AxisStatus, kAxisCount> axes{};
};

// The axis whose alarm the machine reports (status.alarm_axis, a cycle's
// result in the history and its end event): the one that latched the first
// alarm since the last reset, else (a status not from the engine) the first
// axis with an alarm; -1 when none has one.
inline int reported_alarm_axis(const Status& st) {
  const auto first = static_cast<std::size_t>(st.first_alarm_axis);
  if (st.first_alarm_axis >= 0 && first < kAxisCount && st.axes[first].alarm) return st.first_alarm_axis;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (st.axes[a].alarm) return static_cast<int>(a);
  return -1;
}

}  // namespace homing
