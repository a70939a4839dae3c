#pragma once
// Modbus exception codes as values, with a sentence for the log and the HMI.
#include <cstdint>
#include <string>
#include <string_view>

#include "homing/enum_info.hpp"
#include "homing/settings_check.hpp"

namespace registers {

// Numbers are the Modbus exception codes on the wire.
enum class ExceptionCode : std::uint8_t {
  illegal_function = 0x01,
  illegal_data_address = 0x02,
  illegal_data_value = 0x03,
  server_device_failure = 0x04,
  server_device_busy = 0x06,
  gateway_target_failed = 0x0B,  // Modbus TCP: a unit id nothing answers to
};

constexpr std::string_view exception_name(ExceptionCode c) {
  switch (c) {
    case ExceptionCode::illegal_function: return "illegal function";
    case ExceptionCode::illegal_data_address: return "illegal data address";
    case ExceptionCode::illegal_data_value: return "illegal data value";
    case ExceptionCode::server_device_failure: return "server device failure";
    case ExceptionCode::server_device_busy: return "server device busy";
    case ExceptionCode::gateway_target_failed: return "gateway target device failed to respond";
  }
  return "?";
}

// Why a write was refused, published as status.last_refusal_reason (with
// status.last_refused_register and status.refusal_count) so that a PLC can
// tell "illegal data value" apart. A broken configuration rule is published
// as kRuleReasonBase + the rule (homing::CheckRule), one code per rule.
enum class RefusalReason : std::uint8_t {
  none = 0,
  not_mapped,           // no register at that address
  read_only,            // a read-only register or table
  split_32bit,          // a write covering one half of a 32-bit value
  out_of_range,         // a value outside the register's range
  rule,                 // the settings after the write break a rule (published per rule)
  client_read_only,     // the client's address is not in --write-allow
  locked,               // settings are locked (security.unlock)
  wrong_unlock_code,    // the code written to security.unlock is wrong
  busy,                 // a homing cycle runs
  wiring,               // the machine's wiring (GPIO) cannot do it
  storage_failed,       // the settings database did not store it
  carriage_moving,      // simulator: a geometry write to a carriage that moves
  loop_not_responding,  // simulator: the control loop did not take the write in time
  empty,                // a write of 0 items
  hard_stops_inverted,  // simulator: hard_stop_min must be below hard_stop_max
  role,                 // Modbus/TCP Security: the client certificate's role does not allow the write
  no_axis_named,        // cmd.home_axes = 0
  axis_disabled,        // cmd.home_axes names an axis whose mode is disabled
  homing_blocked,       // cmd.home_axes while an alarm, e-stop, drive fault, lost link or missing permit blocks homing
  unlock_locked_out,    // security.unlock after too many wrong codes in a row: not even compared until the lockout ends
  slave_inherits,       // a gantry slave's own value of a setting it takes from its master
  edit_session_open,    // edit.command = begin while this client's edit session is open
  edit_no_session,      // edit.command = commit or discard without an edit session
  edit_session_expired, // a settings write or a commit after the edit session timed out
  edit_mixed,           // in an edit session, one request with settings and other registers
  edit_sessions_full,   // edit.command = begin while the most edit sessions are open
  edit_broadcast,       // edit.command in an RTU broadcast: no answer could say how it went
  malformed_write,      // a write request outside the standard: quantity, byte count or coil value
  no_unlock_code,       // security.unlock or cmd.lock_settings while homingd has no --unlock-code
  beyond_hard_stop,     // simulator: sim.<a>.actual_position outside the carriage's hard stops
};
// Each reason with the exception it is answered with, its name and its text.
struct RefusalReasonInfo {
  RefusalReason value;
  ExceptionCode exception;
  std::string_view name;
  std::string_view text;
};
inline constexpr RefusalReasonInfo kRefusalReasonInfo[] = {
    {RefusalReason::none, ExceptionCode::server_device_failure, "none", "no write refused since start"},
    {RefusalReason::not_mapped, ExceptionCode::illegal_data_address, "not_mapped", "no register at this address (see hmi_maps/registers.md)"},
    {RefusalReason::read_only, ExceptionCode::illegal_data_address, "read_only", "this register or table is read-only"},
    {RefusalReason::split_32bit, ExceptionCode::illegal_data_address, "split_32bit", "a 32-bit value must be written with both words in one request"},
    {RefusalReason::out_of_range, ExceptionCode::illegal_data_value, "out_of_range", "the value is outside the register's range"},
    {RefusalReason::rule, ExceptionCode::illegal_data_value, "rule", "the settings after this write break a rule (published as 100 + rule)"},
    {RefusalReason::client_read_only, ExceptionCode::illegal_function, "client_read_only",
     "this client's address is not allowed to write (homingd --write-allow)"},
    {RefusalReason::locked, ExceptionCode::server_device_failure, "locked", "settings are locked: write the unlock code to security.unlock (a code above 65535: to security.unlock32, both words in one FC 16)"},
    {RefusalReason::wrong_unlock_code, ExceptionCode::illegal_data_value, "wrong_unlock_code", "the unlock code written to security.unlock or security.unlock32 is wrong"},
    {RefusalReason::busy, ExceptionCode::server_device_busy, "busy", "a homing cycle runs: write settings, or a command that needs the machine at rest, when it has ended"},
    {RefusalReason::wiring, ExceptionCode::illegal_data_value, "wiring", "the machine's wiring (GPIO lines) cannot do what these settings ask"},
    {RefusalReason::storage_failed, ExceptionCode::server_device_failure, "storage_failed",
     "the settings database did not store the write (disk full or failing): see the log"},
    {RefusalReason::carriage_moving, ExceptionCode::server_device_busy, "carriage_moving", "simulator: the write moves a carriage, its cams or stops while that carriage moves; write it when the axis rests"},
    {RefusalReason::loop_not_responding, ExceptionCode::server_device_busy, "loop_not_responding",
     "simulator: the control loop did not take the write in time"},
    {RefusalReason::empty, ExceptionCode::illegal_data_value, "empty", "a write of 0 items"},
    {RefusalReason::hard_stops_inverted, ExceptionCode::illegal_data_value, "hard_stops_inverted", "simulator: hard_stop_min must be below hard_stop_max"},
    {RefusalReason::role, ExceptionCode::illegal_function, "role",
     "the role in this client's certificate does not allow the write (Modbus/TCP Security: viewer reads, operator also commands, engineer also settings)"},
    {RefusalReason::no_axis_named, ExceptionCode::illegal_data_value, "no_axis_named",
     "cmd.home_axes names no axis: set the bits of the axes to home"},
    {RefusalReason::axis_disabled, ExceptionCode::illegal_data_value, "axis_disabled",
     "cmd.home_axes names an axis whose mode is disabled"},
    {RefusalReason::homing_blocked, ExceptionCode::server_device_failure, "homing_blocked",
     "homing cannot start now (alarm, e-stop, drive fault, lost link or missing permit): see status.interlocks"},
    {RefusalReason::unlock_locked_out, ExceptionCode::server_device_busy, "unlock_locked_out",
     "too many wrong unlock codes in a row: every unlock is refused until status.unlock_lockout_s reads 0"},
    {RefusalReason::slave_inherits, ExceptionCode::illegal_data_value, "slave_inherits",
     "a gantry slave homes and moves with its master's value of this setting: write it on the master "
     "(status.last_refused_register names it)"},
    {RefusalReason::edit_session_open, ExceptionCode::server_device_busy, "edit_session_open",
     "an edit session of this client is open: commit it (edit.command = 2) or discard it (3) before beginning another"},
    {RefusalReason::edit_no_session, ExceptionCode::illegal_data_value, "edit_no_session",
     "no edit session is open for this client: begin one (edit.command = 1), write the settings, then commit"},
    {RefusalReason::edit_session_expired, ExceptionCode::server_device_failure, "edit_session_expired",
     "this client's edit session timed out (global.edit_timeout_s) and its staged settings were discarded: "
     "begin again (edit.command = 1) or discard (3) to write settings one at a time"},
    {RefusalReason::edit_mixed, ExceptionCode::illegal_data_value, "edit_mixed",
     "in an edit session settings are staged alone: write commands, the heartbeat and targets in their own requests"},
    {RefusalReason::edit_sessions_full, ExceptionCode::server_device_busy, "edit_sessions_full",
     "the most edit sessions (32) are open: try again once another client commits, discards or times out"},
    {RefusalReason::edit_broadcast, ExceptionCode::illegal_data_value, "edit_broadcast",
     "an RTU broadcast (unit 0) cannot begin, commit or discard an edit session, since nothing answers it: address "
     "the module's unit id; settings written by broadcast apply at once"},
    {RefusalReason::malformed_write, ExceptionCode::illegal_data_value, "malformed_write",
     "the write request breaks the standard: a quantity outside 1-123 registers (1-121 for FC 23) or 1-1968 coils, a "
     "byte count that does not match it, or a coil value other than FF00 or 0000; nothing was written"},
    {RefusalReason::no_unlock_code, ExceptionCode::illegal_data_value, "no_unlock_code",
     "homingd runs without an unlock code (--unlock-code): settings cannot be locked, so there is nothing to lock or "
     "unlock; start homingd with --unlock-code to protect the settings"},
    {RefusalReason::beyond_hard_stop, ExceptionCode::illegal_data_value, "beyond_hard_stop",
     "simulator: sim.<a>.actual_position places the carriage beyond its hard stops, where no carriage can be: "
     "place it between sim.<a>.hard_stop_min and hard_stop_max (or move a stop in the same request)"},
};
static_assert(homing::lists_every_value(kRefusalReasonInfo, RefusalReason::beyond_hard_stop));
constexpr std::span<const RefusalReasonInfo> enum_table(RefusalReason) { return kRefusalReasonInfo; }

inline constexpr std::uint16_t kRuleReasonBase = 100;

// A refused request: the code to answer with, what a technician should know,
// why (the reason, and the rule when a rule is broken) and the protocol
// address of the first register the refusal is about.
struct Refusal {
  ExceptionCode code = ExceptionCode::server_device_failure;
  std::string message;
  RefusalReason reason = RefusalReason::none;
  homing::CheckRule rule = homing::CheckRule::none;
  std::uint16_t address = 0;

  // A refusal for a reason, answered with the reason's exception.
  static Refusal because(RefusalReason reason, std::uint16_t address, std::string message,
                         homing::CheckRule rule = homing::CheckRule::none) {
    return Refusal{kRefusalReasonInfo[static_cast<std::size_t>(reason)].exception, std::move(message), reason, rule,
                   address};
  }

  // The value of status.last_refusal_reason.
  constexpr std::uint16_t reason_code() const {
    return reason == RefusalReason::rule ? static_cast<std::uint16_t>(kRuleReasonBase + static_cast<int>(rule))
                                         : static_cast<std::uint16_t>(reason);
  }
};

}  // namespace registers
