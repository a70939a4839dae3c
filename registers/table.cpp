// The rows of the register table. Per-axis registers are declared once (an
// AxisRow) and expanded for x y z a b c at base + stride * axis + offset, so an
// HMI can index them. Everything here is constexpr and checked at compile time:
// a clash of addresses or a default outside its range does not build.
#include "registers/table.hpp"

#include <algorithm>
#include <string>

#include "homing/alarms.hpp"
#include "homing/gantry.hpp"
#include "homing/phases.hpp"
#include "homing/settings.hpp"
#include "homing/sim/config.hpp"
#include "homing/status.hpp"
#include "homing/trust.hpp"
#include "registers/errors.hpp"
#include "registers/fills.hpp"

namespace registers {
namespace {

using homing::kAxisCount;

// A default per axis (most rows have the same default on every axis).
struct Def {
  std::array<std::int64_t, kAxisCount> v{};
  constexpr Def(std::int64_t x) : v{x, x, x, x, x, x} {}  // NOLINT: implicit on purpose
  constexpr Def(std::array<std::int64_t, kAxisCount> a) : v(a) {}
};

// The default of axis.<a>.kind: the engine's default_kind of each axis.
constexpr Def kDefaultKinds = [] {
  std::array<std::int64_t, kAxisCount> v{};
  for (std::size_t a = 0; a < kAxisCount; ++a) v[a] = static_cast<std::int64_t>(homing::default_kind(a));
  return Def{v};
}();

// One declared row. For global rows `offset` is the address; for per-axis rows
// it is the offset inside the axis block.
struct Row {
  std::string_view pattern;
  Table table = Table::holding_register;
  std::uint8_t offset = 0;
  Type type = Type::u16;
  Access access = Access::rw;
  Quantity quantity = Quantity::none;
  std::int64_t min = 0;
  std::int64_t max = 0;
  Def def{0};
  SettingAccess fills{};  // settings rows: the member they fill (fills<&Member>); persisted
  Key key = Key::none;    // every other row
  std::uint8_t slot = 0;
  std::span<const EnumValue> values{};
  std::string_view description;
  Effect effect = Effect::none;
};

// Raw limits shared by many rows (µm or millidegree): ±100 m is far beyond any
// machine and well inside i32.
constexpr std::int64_t kLengthMax = 100'000'000;
constexpr std::int64_t kFeedMax = 60'000;  // mm/min
constexpr std::int64_t kAccelMax = 60'000;  // mm/s²

constexpr Table IR = Table::input_register;
constexpr Table CO = Table::coil;
constexpr Table DI = Table::discrete_input;
constexpr Quantity LEN = Quantity::length_um;
using A = homing::AxisSettings;
using G = homing::GlobalSettings;

// ---- enum values ----
// The engine's enums: names and texts come from their tables in homing/
// (enum_info.hpp), so a register's value list is the engine's own.
template <class Entry, std::size_t N>
constexpr std::array<EnumValue, N> values_of(const Entry (&table)[N]) {
  std::array<EnumValue, N> out{};
  for (std::size_t i = 0; i < N; ++i)
    out[i] = {static_cast<std::int64_t>(table[i].value), table[i].name, table[i].text};
  return out;
}
// The highest value of an enum register: its range follows the engine's table.
template <std::size_t N>
constexpr std::int64_t last_value(const std::array<EnumValue, N>& values) {
  return values[N - 1].value;
}
// Bitmask registers: the value of a bit is its number.
template <std::size_t N>
constexpr std::array<EnumValue, N> bits_of(const homing::interlock::BitInfo (&table)[N]) {
  std::array<EnumValue, N> out{};
  for (std::size_t i = 0; i < N; ++i) out[i] = {table[i].bit, table[i].name, table[i].text};
  return out;
}
constexpr auto kModes = values_of(homing::kModeTable);  // homing/modes.hpp: one row per method
constexpr auto kDirections = values_of(homing::kDirectionInfo);
constexpr auto kPreMoves = values_of(homing::kPreMoveInfo);
constexpr auto kSlaveModes = values_of(homing::kSlaveModeInfo);
constexpr auto kAllowed = values_of(homing::kAllowedWithoutHomingInfo);
constexpr auto kAxisAllowed = values_of(homing::kAxisAllowedWithoutHomingInfo);
constexpr auto kFailurePolicies = values_of(homing::kFailurePolicyInfo);
constexpr auto kKinds = values_of(homing::kAxisKindInfo);
constexpr auto kCamEdges = values_of(homing::kCamEdgeInfo);
constexpr auto kStallDetects = values_of(homing::kStallDetectInfo);
constexpr auto kStates = values_of(homing::kMachineStateInfo);
constexpr auto kCommandResults = values_of(homing::kCommandResultInfo);
constexpr auto kInterlocks = bits_of(homing::interlock::kInfo);
constexpr auto kAlarms = values_of(homing::kAlarmInfo);
constexpr auto kPhases = values_of(homing::kPhaseInfo);
constexpr auto kSimFaults = values_of(homing::sim::kFaultInfo);
constexpr auto kHealthWarnings = values_of(homing::kHealthWarningInfo);
constexpr auto kTrusts = values_of(homing::kTrustInfo);
constexpr auto kGantrySides = values_of(homing::kGantrySideInfo);
// Why a write was refused: the reasons (registers/errors.hpp), then one code
// per configuration rule at kRuleReasonBase + the rule (homing::CheckRule).
constexpr auto kRefusalReasons = [] {
  constexpr std::size_t generic = std::size(kRefusalReasonInfo) - 1;  // without `rule`
  constexpr std::size_t rules = std::size(homing::kCheckRuleInfo) - 1;  // without `none`
  std::array<EnumValue, generic + rules> out{};
  std::size_t n = 0;
  for (const auto& r : kRefusalReasonInfo)
    if (r.value != RefusalReason::rule) out[n++] = {static_cast<std::int64_t>(r.value), r.name, r.text};
  for (const auto& r : homing::kCheckRuleInfo)
    if (r.value != homing::CheckRule::none)
      out[n++] = {kRuleReasonBase + static_cast<std::int64_t>(r.value), r.name, r.text};
  return out;
}();
// Register encodings of axes (not engine enums).
constexpr EnumValue kSlaveOf[] = {{0, "none", "not a slave"},  {1, "x", "slave of X"},
                                  {2, "y", "slave of Y"},      {3, "z", "slave of Z"},
                                  {4, "a", "slave of A"},      {5, "b", "slave of B"},
                                  {6, "c", "slave of C"}};
constexpr EnumValue kAxisBits[] = {{0, "x", "X"}, {1, "y", "Y"}, {2, "z", "Z"},
                                   {3, "a", "A"}, {4, "b", "B"}, {5, "c", "C"}};
constexpr EnumValue kAlarmAxis[] = {{0, "none", "no axis alarm"}, {1, "x", "X"}, {2, "y", "Y"},
                                    {3, "z", "Z"}, {4, "a", "A"},  {5, "b", "B"}, {6, "c", "C"}};

// An HMI's edit session (docs/hmi-integration.md "Edit sessions").
constexpr EnumValue kEditCommands[] = {{0, "none", "nothing (reads 0)"},
                                       {1, "begin", "begin an edit session: settings written from now are staged"},
                                       {2, "commit", "check the staged settings together and apply all or none"},
                                       {3, "discard", "drop the staged settings and end the session"}};
constexpr EnumValue kEditStates[] = {{0, "none", "no edit session: settings writes apply at once"},
                                     {1, "open", "settings writes are staged until the commit"},
                                     {2, "expired", "timed out and discarded: settings writes are refused until begin or discard"}};

// Named for hmi_maps/enums.csv; a static_assert below proves every row's list is here.
constexpr ValueList kValueLists[] = {
    {"mode", kModes},
    {"direction", kDirections},
    {"pre_move_mode", kPreMoves},
    {"slave_of", kSlaveOf},
    {"slave_mode", kSlaveModes},
    {"allowed_without_homing", kAllowed},
    {"axis_allowed_without_homing", kAxisAllowed},
    {"failure_policy", kFailurePolicies},
    {"kind", kKinds},
    {"cam_edge", kCamEdges},
    {"stall_detect", kStallDetects},
    {"axis_mask", kAxisBits},
    {"state", kStates},
    {"command_result", kCommandResults},
    {"interlocks", kInterlocks},
    {"alarm", kAlarms},
    {"alarm_axis", kAlarmAxis},
    {"phase", kPhases},
    {"sim_fault", kSimFaults},
    {"health_warning", kHealthWarnings},
    {"trust", kTrusts},
    {"gantry_side", kGantrySides},
    {"refusal_reason", kRefusalReasons},
    {"edit_command", kEditCommands},
    {"edit_state", kEditStates},
};

// ---- module unit ----
constexpr auto kModuleGlobals = std::to_array<Row>({
    // holding: global settings
    {.pattern = "sequence.step1", .type = Type::bitmask, .max = 63, .def = 4, .fills = fills<&G::sequence_steps>, .slot = 0, .values = kAxisBits, .description = "axes homing together in sequence step 1 (bit 0 = X ... bit 5 = C)"},
    {.pattern = "sequence.step2", .offset = 1, .type = Type::bitmask, .max = 63, .def = 3, .fills = fills<&G::sequence_steps>, .slot = 1, .values = kAxisBits, .description = "axes homing together in sequence step 2"},
    {.pattern = "sequence.step3", .offset = 2, .type = Type::bitmask, .max = 63, .fills = fills<&G::sequence_steps>, .slot = 2, .values = kAxisBits, .description = "axes homing together in sequence step 3"},
    {.pattern = "sequence.step4", .offset = 3, .type = Type::bitmask, .max = 63, .fills = fills<&G::sequence_steps>, .slot = 3, .values = kAxisBits, .description = "axes homing together in sequence step 4"},
    {.pattern = "sequence.step5", .offset = 4, .type = Type::bitmask, .max = 63, .fills = fills<&G::sequence_steps>, .slot = 4, .values = kAxisBits, .description = "axes homing together in sequence step 5"},
    {.pattern = "sequence.step6", .offset = 5, .type = Type::bitmask, .max = 63, .fills = fills<&G::sequence_steps>, .slot = 5, .values = kAxisBits, .description = "axes homing together in sequence step 6"},
    {.pattern = "global.allowed_without_homing", .offset = 10, .type = Type::enumeration, .max = 2, .def = 1, .fills = fills<&G::allowed_without_homing>, .values = kAllowed, .description = "what may move before the machine is homed"},
    {.pattern = "global.alarm_clears_homed", .offset = 11, .max = 1, .def = 1, .fills = fills<&G::alarm_clears_homed>, .description = "flag (0/1): an alarm clears the homed state of every axis"},
    {.pattern = "global.watchdog_ms", .offset = 12, .quantity = Quantity::time_ms, .max = 60'000, .fills = fills<&G::watchdog_ms>, .description = "host watchdog: stop motion started over Modbus when host.heartbeat does not change for this long; 0 = off"},
    {.pattern = "global.history_max_rows", .offset = 14, .type = Type::u32, .min = 100, .max = 1'000'000, .def = 10'000, .fills = fills<&G::history_max_rows>, .description = "rows kept in the audit log and in the homing history each (oldest pruned)", .effect = Effect::history_limits},
    // The health trend (docs/health.md): at most 100 cycles, the fewest runs global.history_max_rows keeps.
    {.pattern = "global.trend_cycles", .offset = 41, .max = 100, .def = 20, .fills = fills<&G::trend_cycles>, .description = "health trend: after each cycle an axis's last this many cycles in the homing history are compared (docs/health.md); 0 = off"},
    {.pattern = "global.trend_growth_pct", .offset = 42, .min = 1, .max = 1000, .def = 50, .fills = fills<&G::trend_growth_pct>, .description = "health trend: hysteresis, latch spread, seek-latch difference or chatter grown by more than this percentage over the trend cycles raises axis.<a>.health_warning"},
    {.pattern = "global.trend_min_change", .offset = 43, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 10, .fills = fills<&G::trend_min_change_mm>, .description = "health trend: a length figure must also have grown by at least this much, in the axis's unit (switch noise does not warn)"},
    {.pattern = "global.single_axis_homing", .offset = 60, .max = 1, .def = 1, .fills = fills<&G::single_axis_homing>, .description = "flag (0/1): axes may be homed alone (cmd.home.<a>, cmd.home_axes); 0 = only cmd.home_all homes, so axes that must home in order are never homed piecemeal"},
    {.pattern = "global.failure_policy", .offset = 61, .type = Type::enumeration, .max = last_value(kFailurePolicies), .fills = fills<&G::failure_policy>, .values = kFailurePolicies, .description = "what a homing cycle does when an axis fails (an alarm) or it is aborted (docs/homing-methods.md \"Failure policy\"); an e-stop, a lost host link, a withdrawn permit or lost settings always stop everything"},
    {.pattern = "global.permit_required", .offset = 13, .max = 1, .fills = fills<&G::permit_required>, .description = "flag (0/1): homing needs host.homing_permit (or the permit input) on"},
    {.pattern = "security.unlock", .offset = 30, .max = 65535, .key = Key::security_unlock, .description = "write the unlock code (homingd --unlock-code) to allow settings writes; reads 0"},
    {.pattern = "security.unlock32", .offset = 32, .type = Type::u32, .max = 4294967295LL, .key = Key::security_unlock, .description = "the unlock code as one 32-bit value (both words in one request, FC 16): for a --unlock-code above 65535; reads 0"},
    {.pattern = "edit.command", .offset = 50, .type = Type::enumeration, .max = 3, .key = Key::edit_command, .values = kEditCommands, .description = "this connection's edit session: 1 begin (settings written from now are staged), 2 commit (checked together, all applied or none), 3 discard; reads 0"},
    {.pattern = "global.edit_timeout_s", .offset = 62, .quantity = Quantity::time_s, .min = 5, .max = 3600, .def = 60, .fills = fills<&G::edit_timeout_s>, .description = "an edit session left this long without a write or a commit is discarded (logged); that client's settings writes are then refused until it begins again or discards"},
    {.pattern = "cmd.home_axes", .offset = 40, .type = Type::bitmask, .max = 63, .key = Key::cmd_home_axes, .values = kAxisBits, .description = "write a bitmask of axes (bit 0 = X ... bit 5 = C): one cycle homes exactly those (with their gantry partners) in sequence-step order (reads back 0)"},
    {.pattern = "host.heartbeat", .offset = 20, .max = 65535, .key = Key::host_heartbeat, .description = "the master changes this at least once per watchdog period (not persisted)"},
    // input registers: status
    {.pattern = "status.map_version", .table = IR, .access = Access::r, .max = 65535, .def = kMapVersion, .key = Key::status_map_version, .description = "version of this register map"},
    {.pattern = "status.state", .table = IR, .offset = 1, .type = Type::enumeration, .access = Access::r, .max = 4, .key = Key::status_state, .values = kStates, .description = "machine state"},
    {.pattern = "status.sequence_step", .table = IR, .offset = 2, .access = Access::r, .max = 6, .key = Key::status_sequence_step, .description = "running sequence step 1..6, 0 when not homing"},
    {.pattern = "status.homing_cycles", .table = IR, .offset = 3, .type = Type::u32, .access = Access::r, .max = 4294967295LL, .key = Key::status_homing_cycles, .description = "homing cycles completed successfully since start"},
    {.pattern = "status.heartbeat", .table = IR, .offset = 5, .access = Access::r, .max = 65535, .key = Key::status_heartbeat, .description = "increments every control period (wraps at 65535)"},
    {.pattern = "status.last_command_result", .table = IR, .offset = 6, .type = Type::enumeration, .access = Access::r, .max = last_value(kCommandResults), .key = Key::status_last_command_result, .values = kCommandResults, .description = "result of the last command coil written"},
    {.pattern = "status.interlocks", .table = IR, .offset = 7, .type = Type::bitmask, .access = Access::r, .max = (1 << homing::interlock::kCount) - 1, .key = Key::status_interlocks, .values = kInterlocks, .description = "what now blocks homing or motion; 0 = free to move"},
    {.pattern = "status.global_alarm", .table = IR, .offset = 8, .type = Type::enumeration, .access = Access::r, .max = last_value(kAlarms), .key = Key::status_global_alarm, .values = kAlarms, .description = "alarm not tied to one axis (e-stop at rest, settings lost)"},
    {.pattern = "status.alarm_axis", .table = IR, .offset = 9, .type = Type::enumeration, .access = Access::r, .max = 6, .key = Key::status_alarm_axis, .values = kAlarmAxis, .description = "the axis that latched the first alarm since the last reset (1 = X ... 6 = C), 0 none: later alarms on other axes do not take its place"},
    {.pattern = "status.command_count", .table = IR, .offset = 11, .access = Access::r, .max = 65535, .key = Key::status_command_count, .description = "commands judged so far (wraps): status.last_command_result is the result of the command that moved it"},
    {.pattern = "status.settings_locked", .table = IR, .offset = 10, .access = Access::r, .max = 1, .key = Key::status_settings_locked, .description = "1 while settings writes are locked (write the unlock code to security.unlock, or to security.unlock32 when above 65535)"},
    {.pattern = "status.refusal_count", .table = IR, .offset = 12, .access = Access::r, .max = 65535, .key = Key::status_refusal_count, .description = "writes refused since start (wraps): when it moves, the two registers below say which and why"},
    {.pattern = "status.last_refused_register", .table = IR, .offset = 13, .access = Access::r, .max = 65535, .key = Key::status_last_refused_register, .description = "protocol address of the register the last refused write was about, the one to change (in the unit written to): for a combination rule the setting the rule names, which may be another than the one written (status.last_refused_write)"},
    {.pattern = "status.last_refusal_reason", .table = IR, .offset = 14, .type = Type::enumeration, .access = Access::r, .max = kRefusalReasons.back().value, .key = Key::status_last_refusal_reason, .values = kRefusalReasons, .description = "why the last write was refused (hmi_maps/refusals.csv); 100 and up: the configuration rule it broke"},
    {.pattern = "status.unlock_lockout_s", .table = IR, .offset = 15, .access = Access::r, .max = 65535, .key = Key::status_unlock_lockout_s, .description = "seconds until security.unlock is tried again after too many wrong codes in a row; 0 = not locked out"},
    {.pattern = "status.wrong_unlock_codes", .table = IR, .offset = 16, .access = Access::r, .max = 65535, .key = Key::status_wrong_unlock_codes, .description = "wrong unlock codes in a row since the last right one (the lockout grows with it)"},
    {.pattern = "edit.state", .table = IR, .offset = 18, .type = Type::enumeration, .access = Access::r, .max = 2, .key = Key::edit_state, .values = kEditStates, .description = "the reading client's edit session: 0 none, 1 open, 2 expired (timed out and discarded)"},
    {.pattern = "edit.staged", .table = IR, .offset = 19, .access = Access::r, .max = 65535, .key = Key::edit_staged, .description = "settings staged in the reading client's open edit session"},
    {.pattern = "status.last_refused_write", .table = IR, .offset = 17, .access = Access::r, .max = 65535, .key = Key::status_last_refused_write, .description = "protocol address of the first register of the last refused write request, as the client wrote it (in the unit written to); status.last_refused_register names the one to change"},
    // input registers: diagnostics of the running daemon
    {.pattern = "diag.loop_periods", .table = IR, .offset = 20, .type = Type::u32, .access = Access::r, .max = 4294967295LL, .key = Key::diag_loop_periods, .description = "control periods run since start"},
    {.pattern = "diag.loop_late_p50_us", .table = IR, .offset = 22, .type = Type::u32, .access = Access::r, .max = 4294967295LL, .key = Key::diag_late_p50_us, .description = "median lateness of a control period's start behind its deadline, µs"},
    {.pattern = "diag.loop_late_p99_us", .table = IR, .offset = 24, .type = Type::u32, .access = Access::r, .max = 4294967295LL, .key = Key::diag_late_p99_us, .description = "99th percentile of control-period lateness, µs"},
    {.pattern = "diag.loop_late_p999_us", .table = IR, .offset = 26, .type = Type::u32, .access = Access::r, .max = 4294967295LL, .key = Key::diag_late_p999_us, .description = "99.9th percentile of control-period lateness, µs"},
    {.pattern = "diag.loop_late_max_us", .table = IR, .offset = 28, .type = Type::u32, .access = Access::r, .max = 4294967295LL, .key = Key::diag_late_max_us, .description = "largest control-period lateness, µs"},
    {.pattern = "diag.engine_step_ns", .table = IR, .offset = 30, .type = Type::u32, .access = Access::r, .max = 4294967295LL, .key = Key::diag_engine_step_ns, .description = "mean time of one engine step, ns"},
    {.pattern = "diag.rss_kb", .table = IR, .offset = 32, .type = Type::u32, .access = Access::r, .max = 4294967295LL, .key = Key::diag_rss_kb, .description = "resident memory of the daemon, KiB"},
    {.pattern = "diag.tcp_clients", .table = IR, .offset = 34, .access = Access::r, .max = 65535, .key = Key::diag_tcp_clients, .description = "TCP clients connected now"},
    // discrete inputs
    {.pattern = "status.alarm", .table = DI, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::status_alarm, .description = "an alarm is latched"},
    {.pattern = "status.homing", .table = DI, .offset = 1, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::status_homing, .description = "a homing cycle runs"},
    {.pattern = "status.estop", .table = DI, .offset = 2, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::status_estop, .description = "emergency stop is active"},
    // coils
    {.pattern = "cmd.home_all", .table = CO, .type = Type::boolean, .access = Access::w, .max = 1, .key = Key::cmd_home_all, .description = "write 1: home all axes in sequence (reads back 0)"},
    {.pattern = "cmd.abort", .table = CO, .offset = 1, .type = Type::boolean, .access = Access::w, .max = 1, .key = Key::cmd_abort, .description = "write 1: stop every motion within its deceleration distance"},
    {.pattern = "cmd.reset_alarm", .table = CO, .offset = 2, .type = Type::boolean, .access = Access::w, .max = 1, .key = Key::cmd_reset_alarm, .description = "write 1: clear latched alarms once their cause is gone"},
    {.pattern = "cmd.lock_settings", .table = CO, .offset = 4, .type = Type::boolean, .access = Access::w, .max = 1, .key = Key::cmd_lock_settings, .description = "write 1: lock settings writes again (when homingd has an unlock code)"},
    {.pattern = "host.homing_permit", .table = CO, .offset = 3, .type = Type::boolean, .access = Access::rw, .max = 1, .key = Key::host_homing_permit, .description = "held by the PLC: homing permitted (used when global.permit_required = 1)"},
});

constexpr auto kModuleAxisRows = std::to_array<Row>({
    // holding: per-axis settings
    {.pattern = "axis.<a>.mode", .type = Type::enumeration, .max = last_value(kModes), .def = Def{{2, 2, 2, 0, 0, 0}}, .fills = fills<&A::mode>, .values = kModes, .description = "homing mode"},
    {.pattern = "axis.<a>.direction", .offset = 1, .type = Type::enumeration, .max = 1, .fills = fills<&A::direction>, .values = kDirections, .description = "seek direction"},
    {.pattern = "axis.<a>.seek_feedrate", .offset = 2, .quantity = Quantity::feedrate_per_min, .min = 1, .max = kFeedMax, .def = 1000, .fills = fills<&A::seek_feedrate_mm_per_min>, .description = "speed while searching for the sensor"},
    {.pattern = "axis.<a>.latch_feedrate", .offset = 3, .quantity = Quantity::feedrate_per_min, .min = 1, .max = kFeedMax, .def = 100, .fills = fills<&A::latch_feedrate_mm_per_min>, .description = "slow speed for locating the edge; must be below seek_feedrate"},
    {.pattern = "axis.<a>.acceleration", .offset = 4, .quantity = Quantity::acceleration_per_s2, .min = 1, .max = kAccelMax, .def = 500, .fills = fills<&A::acceleration_mm_per_s2>, .description = "acceleration of every homing move; stop distance = v²/2a"},
    {.pattern = "axis.<a>.debounce_ms", .offset = 5, .quantity = Quantity::time_ms, .max = 1000, .fills = fills<&A::debounce_ms>, .description = "time a sensor change must persist to count"},
    {.pattern = "axis.<a>.final_move_enable", .offset = 6, .max = 1, .fills = fills<&A::final_move_enable>, .description = "flag (0/1): move to final_position after homing"},
    {.pattern = "axis.<a>.sensor_nc", .offset = 7, .max = 1, .fills = fills<&A::sensor_nc>, .description = "flag (0/1): home sensor is normally closed"},
    {.pattern = "axis.<a>.pre_move_mode", .offset = 8, .type = Type::enumeration, .max = 2, .fills = fills<&A::pre_move_mode>, .values = kPreMoves, .description = "move away from the sensor before seeking"},
    {.pattern = "axis.<a>.slave_of", .offset = 9, .type = Type::enumeration, .max = 6, .fills = fills<&A::slave_of>, .values = kSlaveOf, .description = "this axis is the slaved second motor of another axis (1 = X ... 6 = C)"},
    {.pattern = "axis.<a>.slave_mode", .offset = 10, .type = Type::enumeration, .max = 1, .fills = fills<&A::slave_mode>, .values = kSlaveModes, .description = "how a slave axis is driven"},
    {.pattern = "axis.<a>.soft_limits_enable", .offset = 11, .max = 1, .fills = fills<&A::soft_limits_enable>, .description = "flag (0/1): enforce soft_limit_min/max once homed"},
    {.pattern = "axis.<a>.shared_limit", .offset = 12, .max = 1, .fills = fills<&A::shared_limit>, .description = "flag (0/1): after homing the home sensor acts as a hard limit"},
    {.pattern = "axis.<a>.jog_feedrate", .offset = 13, .quantity = Quantity::feedrate_per_min, .min = 1, .max = kFeedMax, .def = 1000, .fills = fills<&A::jog_feedrate_mm_per_min>, .description = "speed of jog and move commands"},
    {.pattern = "axis.<a>.drive_home_timeout_s", .offset = 15, .quantity = Quantity::time_s, .max = 3600, .def = 60, .fills = fills<&A::drive_home_timeout_s>, .description = "drive mode: the drive must report home done within this time after the home request (the longest homing of the drive, with margin)"},
    // Offset 14 stays unmapped: the exception tests write there as a gap inside a block.
    {.pattern = "axis.<a>.kind", .offset = 16, .type = Type::enumeration, .max = 1, .def = kDefaultKinds, .fills = fills<&A::kind>, .values = kKinds, .description = "linear (mm) or rotary (deg, A B C only): the unit of every length, feedrate and acceleration of the axis; a slave has its master's"},
    {.pattern = "axis.<a>.indexer_lock", .offset = 18, .max = 1, .fills = fills<&A::indexer_lock>, .description = "flag (0/1): locking indexer: unlock (and wait for unlocked) before the axis moves, lock again at rest (docs/homing-methods.md \"Locking indexer\")"},
    {.pattern = "axis.<a>.lock_timeout_ms", .offset = 19, .quantity = Quantity::time_ms, .min = 1, .max = 60'000, .def = 2'000, .fills = fills<&A::lock_timeout_ms>, .description = "locking indexer: unlocked (before motion) and locked (after rest) must be reported within this time, else an alarm"},
    {.pattern = "axis.<a>.allowed_without_homing", .offset = 66, .type = Type::enumeration, .max = last_value(kAxisAllowed), .fills = fills<&A::allowed_without_homing>, .values = kAxisAllowed, .description = "what this axis may do before it is homed: 0 = as global.allowed_without_homing, else its own (Repetier MOVE_<axis>_WHEN_HOMED)"},
    {.pattern = "axis.<a>.max_seek_travel", .offset = 20, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 500'000, .fills = fills<&A::max_seek_travel_mm>, .description = "sensor not found within this travel: alarm"},
    {.pattern = "axis.<a>.max_stop_distance", .offset = 22, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 10'000, .fills = fills<&A::max_stop_distance_mm>, .description = "the axis must stop within this distance after the trigger"},
    {.pattern = "axis.<a>.max_backoff", .offset = 24, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 10'000, .fills = fills<&A::max_backoff_mm>, .description = "the sensor must release within this back-off travel"},
    {.pattern = "axis.<a>.pull_off", .offset = 26, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 1'000, .fills = fills<&A::pull_off_mm>, .description = "move away from the reference edge after locating it"},
    {.pattern = "axis.<a>.home_position", .offset = 28, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .fills = fills<&A::home_position_mm>, .description = "machine coordinate assigned to the resting point after pull-off"},
    {.pattern = "axis.<a>.final_position", .offset = 30, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .fills = fills<&A::final_position_mm>, .description = "absolute move target after homing (final_move_enable or mode 6)"},
    {.pattern = "axis.<a>.pre_move_distance", .offset = 32, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 5'000, .fills = fills<&A::pre_move_distance_mm>, .description = "distance of the pre-move"},
    {.pattern = "axis.<a>.push_distance", .offset = 34, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 2'000, .fills = fills<&A::push_distance_mm>, .description = "pushing modes: distance pushed into the mechanical stop"},
    {.pattern = "axis.<a>.index_pitch", .offset = 36, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 5'000, .fills = fills<&A::index_pitch_mm>, .description = "travel per encoder index pulse; bounds the index phase"},
    {.pattern = "axis.<a>.max_misalignment", .offset = 38, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 2'000, .fills = fills<&A::max_misalignment_mm>, .description = "gantry: largest master/slave difference accepted"},
    {.pattern = "axis.<a>.switch_compensation", .offset = 40, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .fills = fills<&A::switch_compensation_mm>, .description = "gantry: fine correction added to the slave's edge"},
    {.pattern = "axis.<a>.soft_limit_min", .offset = 42, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .def = -1'000'000, .fills = fills<&A::soft_limit_min_mm>, .description = "lowest position allowed once homed"},
    {.pattern = "axis.<a>.soft_limit_max", .offset = 44, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .def = 1'000'000, .fills = fills<&A::soft_limit_max_mm>, .description = "highest position allowed once homed"},
    {.pattern = "axis.<a>.limits_fitted", .offset = 46, .max = 1, .fills = fills<&A::limits_fitted>, .description = "flag (0/1): end-of-travel limit switches at both ends (limit_min, limit_max): hard limits outside homing, reversal points of home_cam (docs/limit-switches.md)"},
    // Offset 50 stays unmapped: the exception tests probe it as a gap (address 150).
    {.pattern = "axis.<a>.limits_nc", .offset = 47, .max = 1, .fills = fills<&A::limits_nc>, .description = "flag (0/1): the limit switches are normally closed (a broken wire reads as a tripped limit)"},
    {.pattern = "axis.<a>.cam_edge", .offset = 51, .type = Type::enumeration, .max = 1, .fills = fills<&A::cam_edge>, .values = kCamEdges, .description = "home_cam: the edge of the cam that is the reference, behind (facing away from direction) or ahead (toward direction)"},
    {.pattern = "axis.<a>.limit_overtravel", .offset = 48, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 10'000, .fills = fills<&A::limit_overtravel_mm>, .description = "travel past a limit switch before the mechanical stop: the axis must stop within it from its seek and jog feedrates"},
    {.pattern = "axis.<a>.stall_timeout_ms", .offset = 52, .type = Type::u32, .quantity = Quantity::time_ms, .max = 3'600'000, .def = 30'000, .fills = fills<&A::stall_timeout_ms>, .description = "hard-stop homing: the drive must report a stall within this time of pushing toward the stop (stall_timeout alarm)"},
    {.pattern = "axis.<a>.latch_passes", .offset = 54, .min = 1, .max = homing::kMaxLatchPasses, .def = 1, .fills = fills<&A::latch_passes>, .description = "re-approach methods: slow approaches to the reference edge in one cycle; the reference is their median, their spread and sigma are published (1 = one approach; docs/health.md)"},
    {.pattern = "axis.<a>.max_latch_spread", .offset = 56, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 50, .fills = fills<&A::max_latch_spread_mm>, .description = "with several latch passes: their spread (max - min) above this raises switch_not_repeatable"},
    {.pattern = "axis.<a>.max_skew_change", .offset = 58, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 100, .fills = fills<&A::max_skew_change_mm>, .description = "gantry slave: the last cycle's skew (axis.<a>.gantry_skew) this much away from what it was over the trend cycles raises the health warning gantry_skew_changed; 0 = not checked (docs/health.md)"},
    // Hard-stop homing by the encoder (docs/homing-methods.md "Hard-stop homing by following error").
    {.pattern = "axis.<a>.stall_detect", .offset = 64, .type = Type::enumeration, .max = last_value(kStallDetects), .fills = fills<&A::stall_detect>, .values = kStallDetects, .description = "hard-stop homing: how the stop is told, the drive's stall input (0) or the encoder's following error (1: the carriage falls behind its steps by more than max_following_error)"},
    {.pattern = "axis.<a>.max_following_error", .offset = 62, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 200, .fills = fills<&A::max_following_error_mm>, .description = "hard-stop homing by following error: the commanded position may lead the encoder by this much before the carriage counts as stopped against the stop"},
    // Position trust across restarts (docs/homing-methods.md "Position trust and the reference check").
    {.pattern = "axis.<a>.refcheck_tolerance", .offset = 67, .type = Type::u32, .quantity = LEN, .min = 1, .max = 10'000, .def = 100, .fills = fills<&A::refcheck_tolerance_mm>, .description = "reference check after a restart: the switch edge must be found within this of where the stored position puts it, or the check is refused and a full cycle is needed"},
    {.pattern = "axis.<a>.target", .offset = 60, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .key = Key::host_target, .description = "target of cmd.move.<a> (not persisted)"},
    // input registers: per-axis status
    {.pattern = "axis.<a>.phase", .table = IR, .type = Type::enumeration, .access = Access::r, .max = last_value(kPhases), .key = Key::axis_phase, .values = kPhases, .description = "what the axis is doing"},
    {.pattern = "axis.<a>.alarm", .table = IR, .offset = 1, .type = Type::enumeration, .access = Access::r, .max = last_value(kAlarms), .key = Key::axis_alarm, .values = kAlarms, .description = "latched alarm code, 0 none"},
    {.pattern = "axis.<a>.alarm_phase", .table = IR, .offset = 2, .type = Type::enumeration, .access = Access::r, .max = last_value(kPhases), .key = Key::axis_alarm_phase, .values = kPhases, .description = "phase in which the alarm was raised"},
    {.pattern = "axis.<a>.alarm_rule", .table = IR, .offset = 3, .access = Access::r, .max = 255, .key = Key::axis_alarm_rule, .description = "the alarm's detail: for limit_switch and limit_in_homing the end whose switch it was, 1 = negative, 2 = positive; for settings_fault the rule broken (its code in hmi_maps/refusals.csv); 0 otherwise"},
    {.pattern = "axis.<a>.position", .table = IR, .offset = 4, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_position, .description = "position in machine coordinates"},
    {.pattern = "axis.<a>.velocity", .table = IR, .offset = 6, .type = Type::i32, .access = Access::r, .quantity = Quantity::velocity_um_per_s, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_velocity, .description = "velocity now"},
    {.pattern = "axis.<a>.home_correction", .table = IR, .offset = 8, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_home_correction, .description = "assigned minus believed position at the reference edge, last homing"},
    {.pattern = "axis.<a>.stop_distance", .table = IR, .offset = 10, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_stop_distance, .description = "v²/2a of the seek (plus travel during debounce)"},
    {.pattern = "axis.<a>.trigger_position", .table = IR, .offset = 12, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_trigger_position, .description = "where the reference edge was found, in the coordinates believed before assign"},
    {.pattern = "axis.<a>.phase_distance", .table = IR, .offset = 14, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_phase_distance, .description = "travelled in the current phase"},
    {.pattern = "axis.<a>.correction_mean", .table = IR, .offset = 16, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_correction_mean, .description = "mean home correction over the recorded history"},
    {.pattern = "axis.<a>.alarm_value", .table = IR, .offset = 20, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_alarm_value, .description = "the figure the alarm text quotes (distance, misalignment, position), 0 without alarm; in the axis's unit unless alarms.csv's alarm_value_unit says s (seconds) or setting"},
    {.pattern = "axis.<a>.correction_spread", .table = IR, .offset = 18, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_correction_spread, .description = "spread (max - min) of the last 10 home corrections"},
    {.pattern = "axis.<a>.latch_spread", .table = IR, .offset = 22, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_latch_spread, .description = "last homing: spread (max - min) of the latch passes' edges (docs/health.md)"},
    {.pattern = "axis.<a>.latch_sigma", .table = IR, .offset = 24, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_latch_sigma, .description = "last homing: standard deviation of the latch passes' edges"},
    {.pattern = "axis.<a>.latch_passes_done", .table = IR, .offset = 26, .access = Access::r, .max = homing::kMaxLatchPasses, .key = Key::axis_latch_passes_done, .description = "last homing: latch passes made (0 when its method does not re-approach)"},
    {.pattern = "axis.<a>.hysteresis", .table = IR, .offset = 28, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_hysteresis, .description = "last homing: distance between the switch's trigger and release edges (docs/health.md)"},
    {.pattern = "axis.<a>.seek_latch_difference", .table = IR, .offset = 30, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_seek_latch_difference, .description = "last homing: seek edge minus latch edge along the seek (the input's latency times the speed difference)"},
    {.pattern = "axis.<a>.chatter_edges", .table = IR, .offset = 32, .access = Access::r, .max = 65535, .key = Key::axis_chatter_edges, .description = "last homing: switch transitions swallowed by the debounce time (contact chatter)"},
    {.pattern = "axis.<a>.index_distance", .table = IR, .offset = 34, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_index_distance, .description = "last homing, switch + index: distance from the switch's release edge to the index pulse taken (docs/health.md)"},
    {.pattern = "axis.<a>.index_near_edge", .table = IR, .offset = 36, .access = Access::r, .max = 1, .key = Key::axis_index_near_edge, .description = "warning (0/1): the index pulse lies within 10 % of a pitch of the switch edge or of one pitch from it, so switch noise can home one revolution off; move the cam or the encoder's index by about half a pitch"},
    {.pattern = "axis.<a>.gantry_skew", .table = IR, .offset = 37, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_gantry_skew, .description = "last homing, gantry slave: its reference edge minus its master's, each from where its side stood at the start (the squaring before switch_compensation; docs/health.md); 0 on other axes"},
    {.pattern = "axis.<a>.health_warning", .table = IR, .offset = 40, .type = Type::enumeration, .access = Access::r, .max = last_value(kHealthWarnings), .key = Key::axis_health_warning, .values = kHealthWarnings, .description = "what the trend of the homing history says of this axis's switch or gantry (a warning, not an alarm: the axis stays homed; docs/health.md)"},
    {.pattern = "axis.<a>.trust", .table = IR, .offset = 41, .type = Type::enumeration, .access = Access::r, .max = last_value(kTrusts), .key = Key::axis_trust, .values = kTrusts, .description = "how far the axis's position can be believed: unknown, last_stop_clean (a reference check is offered: cmd.refcheck.<a>), reference_checked, homed_this_power_on"},
    {.pattern = "axis.<a>.refcheck_error", .table = IR, .offset = 42, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_refcheck_error, .description = "last reference check: where the switch edge was found less where the stored position put it (refused beyond refcheck_tolerance; when the edge was not found at all, as far as the search went)"},
    // A gantry's misalignment alarm, on the slave (docs/homing-methods.md "Gantries: racking"): with
    // axis.<a>.alarm_value (how far out of square) they read as the log's text does.
    {.pattern = "axis.<a>.alarm_side", .table = IR, .offset = 39, .type = Type::enumeration, .access = Access::r, .max = last_value(kGantrySides), .key = Key::axis_alarm_side, .values = kGantrySides, .description = "misalignment alarm: the side of the gantry that carried the pair out, master or slave, and whether it had found its home sensor; 0 for every other alarm"},
    {.pattern = "axis.<a>.alarm_rack_at_start", .table = IR, .offset = 52, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_alarm_rack_at_start, .description = "misalignment alarm: how far out of square (slave minus master) the pair stood when the cycle started, 0 when it started square (an earlier alarm can leave it racked)"},
    // The commissioning measurement (docs/homing-methods.md "Commissioning measurement"): 0 until one found its end.
    {.pattern = "axis.<a>.measured_travel", .table = IR, .offset = 44, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_measured_travel, .description = "last measurement (cmd.measure.<a>): usable travel from home_position toward the opposite end, where the end was found less the stop distance from jog_feedrate"},
    {.pattern = "axis.<a>.measured_soft_limit_min", .table = IR, .offset = 46, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_measured_soft_limit_min, .description = "last measurement: suggested soft_limit_min (machine coordinates; written only by homingctl measure --apply)"},
    {.pattern = "axis.<a>.measured_soft_limit_max", .table = IR, .offset = 48, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_measured_soft_limit_max, .description = "last measurement: suggested soft_limit_max (machine coordinates; written only by homingctl measure --apply)"},
    {.pattern = "axis.<a>.measured_max_seek_travel", .table = IR, .offset = 50, .type = Type::i32, .access = Access::r, .quantity = LEN, .min = type_min(Type::i32), .max = type_max(Type::i32), .key = Key::axis_measured_max_seek_travel, .description = "last measurement: suggested max_seek_travel, the longest seek (from the far end to the sensor or stop, plus max_stop_distance) plus 10 % (at least 5 mm), in whole mm"},
    // discrete inputs
    {.pattern = "axis.<a>.homed", .table = DI, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::axis_homed, .description = "the axis is homed (cleared by an alarm per global.alarm_clears_homed, and when a setting of its home frame changes: home_position, pull_off, switch_compensation, mode, direction, sensor_nc, slave_of, slave_mode, and cam_edge for a home cam)"},
    {.pattern = "axis.<a>.sensor", .table = DI, .offset = 1, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::axis_sensor, .description = "home sensor active (debounced, polarity applied)"},
    {.pattern = "axis.<a>.busy", .table = DI, .offset = 2, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::axis_busy, .description = "the axis is moving or homing"},
    {.pattern = "axis.<a>.limit_min", .table = DI, .offset = 3, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::axis_limit_min, .description = "the negative end's limit switch is active (limits_fitted, limits_nc applied; 0 without limit switches): the wiring can be checked by hand"},
    {.pattern = "axis.<a>.limit_max", .table = DI, .offset = 4, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::axis_limit_max, .description = "the positive end's limit switch is active (limits_fitted, limits_nc applied; 0 without limit switches)"},
    // coils
    {.pattern = "cmd.home.<a>", .table = CO, .type = Type::boolean, .access = Access::w, .max = 1, .key = Key::cmd_home, .description = "write 1: home this axis alone (reads back 0)"},
    {.pattern = "cmd.jog_plus.<a>", .table = CO, .offset = 1, .type = Type::boolean, .access = Access::rw, .max = 1, .key = Key::cmd_jog_plus, .description = "jog positive while 1; 0 stops (reads back the held state)"},
    {.pattern = "cmd.jog_minus.<a>", .table = CO, .offset = 2, .type = Type::boolean, .access = Access::rw, .max = 1, .key = Key::cmd_jog_minus, .description = "jog negative while 1; 0 stops (reads back the held state)"},
    {.pattern = "cmd.unhome.<a>", .table = CO, .offset = 4, .type = Type::boolean, .access = Access::w, .max = 1, .key = Key::cmd_unhome, .description = "write 1: forget this axis's reference (and its gantry partner's) without moving; refused while it moves or a cycle runs (reads back 0)"},
    {.pattern = "cmd.set_position.<a>", .table = CO, .offset = 6, .type = Type::boolean, .access = Access::w, .max = 1, .key = Key::cmd_set_position, .description = "write 1: this unhomed axis's coordinate becomes axis.<a>.target where it stands, without moving (it stays unhomed); refused while homed, moving or a gantry slave; audited with the client (reads back 0)"},
    {.pattern = "cmd.refcheck.<a>", .table = CO, .offset = 5, .type = Type::boolean, .access = Access::w, .max = 1, .key = Key::cmd_refcheck, .description = "write 1: reference check of this axis after a restart (axis.<a>.trust last_stop_clean): find its switch edge at latch feedrate near where its stored position puts it; homed when within refcheck_tolerance (reads back 0)"},
    {.pattern = "cmd.measure.<a>", .table = CO, .offset = 7, .type = Type::boolean, .access = Access::w, .max = 1, .key = Key::cmd_measure, .description = "write 1: commissioning measurement of this axis: home it alone, then travel at latch_feedrate to the opposite limit switch or hard stop (within max_seek_travel) and publish axis.<a>.measured_*; writes no setting (reads back 0)"},
    {.pattern = "cmd.move.<a>", .table = CO, .offset = 3, .type = Type::boolean, .access = Access::w, .max = 1, .key = Key::cmd_move, .description = "write 1: move to axis.<a>.target at jog_feedrate (reads back 0)"},
});

// ---- simulator unit (never persisted: the simulated machine starts from these) ----
constexpr auto kSimGlobals = std::to_array<Row>({
    {.pattern = "sim.seed", .type = Type::u32, .max = 4294967295LL, .def = 1, .key = Key::sim_seed, .description = "seed of the noise generator; writing it restarts the sequence"},
    {.pattern = "sim.estop", .table = CO, .type = Type::boolean, .max = 1, .key = Key::sim_estop, .description = "1 = emergency stop pressed"},
    {.pattern = "sim.start_button", .table = CO, .offset = 1, .type = Type::boolean, .max = 1, .key = Key::sim_start_button, .description = "the physical start button (1 = pressed)"},
});

constexpr auto kSimAxisRows = std::to_array<Row>({
    {.pattern = "sim.<a>.actual_position", .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .def = 100'000, .key = Key::sim_actual_position, .description = "where the carriage really is; writing places it (exception 06 while the axis moves, 03 beyond its hard stops)"},
    {.pattern = "sim.<a>.sensor_min", .offset = 2, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .def = -1'000'000, .key = Key::sim_sensor_min, .description = "the cam holding the home sensor active starts here"},
    {.pattern = "sim.<a>.sensor_max", .offset = 4, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .def = 0, .key = Key::sim_sensor_max, .description = "the cam holding the home sensor active ends here"},
    {.pattern = "sim.<a>.hysteresis", .offset = 6, .quantity = LEN, .max = 65535, .def = 50, .key = Key::sim_hysteresis, .description = "the sensor turns inactive this far outside the cam"},
    {.pattern = "sim.<a>.noise", .offset = 7, .quantity = LEN, .max = 65535, .def = 2, .key = Key::sim_noise, .description = "standard deviation of each edge's position"},
    {.pattern = "sim.<a>.bounce_ms", .offset = 8, .quantity = Quantity::time_ms, .max = 1000, .key = Key::sim_bounce_ms, .description = "contact bounce after each edge"},
    {.pattern = "sim.<a>.sensor_nc", .offset = 9, .max = 1, .key = Key::sim_sensor_nc, .description = "flag (0/1): the simulated switch is wired normally closed"},
    {.pattern = "sim.<a>.hard_stop_min", .offset = 10, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .def = -5'000, .key = Key::sim_hard_stop_min, .description = "lower mechanical stop; a motor pushed against it loses steps"},
    {.pattern = "sim.<a>.hard_stop_max", .offset = 12, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .def = 1'000'000, .key = Key::sim_hard_stop_max, .description = "upper mechanical stop"},
    {.pattern = "sim.<a>.index_pitch", .offset = 14, .type = Type::i32, .quantity = LEN, .max = kLengthMax, .def = 0, .key = Key::sim_index_pitch, .description = "travel between encoder index pulses; 0 = no index"},
    {.pattern = "sim.<a>.index_offset", .offset = 16, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .key = Key::sim_index_offset, .description = "position of one index pulse"},
    {.pattern = "sim.<a>.absolute_offset", .offset = 18, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .key = Key::sim_absolute_offset, .description = "the absolute encoder reads actual_position + this"},
    {.pattern = "sim.<a>.fault", .offset = 20, .type = Type::enumeration, .max = last_value(kSimFaults), .key = Key::sim_fault, .values = kSimFaults, .description = "injected fault"},
    {.pattern = "sim.<a>.lose_steps", .offset = 22, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .key = Key::sim_lose_steps, .description = "writing N shifts the carriage by N without the controller knowing; reads back 0"},
    {.pattern = "sim.<a>.drive_home_position", .offset = 24, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .key = Key::sim_drive_home_position, .description = "drive mode: where the drive's own homing ends (its own home sensor), in carriage position"},
    {.pattern = "sim.<a>.drive_speed", .offset = 26, .quantity = Quantity::feedrate_per_min, .min = 1, .max = kFeedMax, .def = 600, .key = Key::sim_drive_speed, .description = "drive mode: the speed at which the drive moves the carriage to its home"},
    {.pattern = "sim.<a>.drive_answer_ms", .offset = 27, .quantity = Quantity::time_ms, .max = 60'000, .def = 100, .key = Key::sim_drive_answer_ms, .description = "drive mode: time the drive takes after reaching its home before it reports home done"},
    {.pattern = "sim.<a>.unlock_delay_ms", .offset = 28, .quantity = Quantity::time_ms, .max = 60'000, .def = 100, .key = Key::sim_unlock_delay_ms, .description = "locking indexer (fitted when axis.<a>.indexer_lock is on): time from the unlock output to the pin being out"},
    {.pattern = "sim.<a>.lock_delay_ms", .offset = 29, .quantity = Quantity::time_ms, .max = 60'000, .def = 100, .key = Key::sim_lock_delay_ms, .description = "locking indexer: time from the unlock output going off to the pin being in"},
    {.pattern = "sim.<a>.limit_min", .offset = 30, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .def = -kLengthMax, .key = Key::sim_limit_min, .description = "the negative end's limit switch is active with the carriage at or below this (its cam runs on to the mechanical stop); the default lies beyond any stop"},
    {.pattern = "sim.<a>.limit_max", .offset = 32, .type = Type::i32, .quantity = LEN, .min = -kLengthMax, .max = kLengthMax, .def = kLengthMax, .key = Key::sim_limit_max, .description = "the positive end's limit switch is active with the carriage at or above this"},
    {.pattern = "sim.<a>.limits_nc", .offset = 34, .max = 1, .key = Key::sim_limits_nc, .description = "flag (0/1): the simulated limit switches are wired normally closed"},
    {.pattern = "sim.<a>.sensor", .table = DI, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::sim_sensor, .description = "the simulated switch is active (raw, before polarity and debounce)"},
    {.pattern = "sim.<a>.at_hard_stop", .table = DI, .offset = 1, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::sim_at_hard_stop, .description = "the carriage rests against a mechanical stop"},
    {.pattern = "sim.<a>.indexer_locked", .table = DI, .offset = 2, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::sim_indexer_locked, .description = "the simulated locking indexer's pin is in and holds the carriage"},
    {.pattern = "sim.<a>.limit_min_active", .table = DI, .offset = 3, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::sim_limit_min_active, .description = "the simulated negative-end limit switch is active (raw, before polarity)"},
    {.pattern = "sim.<a>.limit_max_active", .table = DI, .offset = 4, .type = Type::boolean, .access = Access::r, .max = 1, .key = Key::sim_limit_max_active, .description = "the simulated positive-end limit switch is active (raw, before polarity)"},
    {.pattern = "sim.<a>.driven_by", .table = IR, .access = Access::r, .max = 6, .key = Key::sim_driven_by, .description = "the step output that moves this carriage: 0 its own; 1..6 that of master X..C, through an external commutator (from axis.<a>.slave_of and slave_mode)"},
});

// ---- expansion ----
constexpr Register expand_row(Unit unit, const Row& r, int axis) {
  Register g{};
  g.pattern = r.pattern;
  g.unit = unit;
  g.table = r.table;
  g.type = r.type;
  g.access = r.access;
  g.quantity = r.quantity;
  g.min = r.min;
  g.max = r.max;
  g.persisted = r.fills.bound();
  g.setting = r.fills;
  g.key = r.key;
  g.slot = r.slot;
  g.values = r.values;
  g.description = r.description;
  g.effect = r.effect;
  if (axis < 0) {
    g.address = r.offset;
    g.default_raw = r.def.v[0];
  } else {
    const AxisBlock b = axis_block(r.table);
    g.address = static_cast<std::uint16_t>(b.base + b.stride * axis + r.offset);
    g.default_raw = r.def.v[static_cast<std::size_t>(axis)];
    g.axis = static_cast<std::int8_t>(axis);
    g.offset = r.offset;
  }
  return g;
}

constexpr bool before(const Register& a, const Register& b) {
  if (a.unit != b.unit) return a.unit < b.unit;
  if (a.table != b.table) return a.table < b.table;
  return a.address < b.address;
}

template <std::size_t G, std::size_t A>
constexpr auto expand(Unit unit, const std::array<Row, G>& globals, const std::array<Row, A>& axes) {
  std::array<Register, G + A * kAxisCount> out{};
  std::size_t n = 0;
  for (const Row& r : globals) out[n++] = expand_row(unit, r, -1);
  for (const Row& r : axes)
    for (std::size_t a = 0; a < kAxisCount; ++a) out[n++] = expand_row(unit, r, static_cast<int>(a));
  return out;
}

template <std::size_t M, std::size_t S>
constexpr auto join_sorted(const std::array<Register, M>& m, const std::array<Register, S>& s) {
  std::array<Register, M + S> out{};
  std::copy(m.begin(), m.end(), out.begin());
  std::copy(s.begin(), s.end(), out.begin() + M);
  std::sort(out.begin(), out.end(), before);
  return out;
}

constexpr auto kAll = join_sorted(expand(Unit::module, kModuleGlobals, kModuleAxisRows),
                                  expand(Unit::simulator, kSimGlobals, kSimAxisRows));

// ---- compile-time checks of the table ----
constexpr bool addresses_unique_without_overlap() {
  for (std::size_t i = 1; i < kAll.size(); ++i) {
    const Register& p = kAll[i - 1];
    const Register& r = kAll[i];
    if (p.unit == r.unit && p.table == r.table && p.end() > r.address) return false;
  }
  return true;
}
constexpr bool ranges_fit_types() {
  for (const Register& r : kAll) {
    if (r.min < type_min(r.type) || r.max > type_max(r.type) || r.min > r.max) return false;
    if (r.default_raw < r.min || r.default_raw > r.max) return false;
  }
  return true;
}
constexpr bool blocks_fit_strides() {
  for (const Register& r : kAll) {
    const AxisBlock b = axis_block(r.table);
    if (r.per_axis() && r.offset + r.words() > b.stride) return false;
    if (!r.per_axis() && r.end() > b.base) return false;  // globals below the first axis block
    if (r.end() > 65536) return false;
  }
  return true;
}
constexpr bool kinds_consistent() {
  for (const Register& r : kAll) {
    const bool bit_table = r.table == Table::coil || r.table == Table::discrete_input;
    if (bit_table != (r.type == Type::boolean)) return false;
    if ((r.table == Table::discrete_input || r.table == Table::input_register) && r.access != Access::r)
      return false;
    if (r.table == Table::holding_register && r.access != Access::rw) return false;
    if (r.access == Access::w && r.table != Table::coil) return false;
    if (r.persisted && (r.table != Table::holding_register || r.unit != Unit::module)) return false;
    if ((r.type == Type::enumeration || r.type == Type::bitmask) && r.values.empty()) return false;
    if (r.type == Type::enumeration && (r.values.front().value != r.min || r.values.back().value != r.max))
      return false;
    if (r.type == Type::bitmask && r.max != (std::int64_t{1} << r.values.size()) - 1) return false;
    if (r.per_axis() != (r.pattern.find("<a>") != std::string_view::npos)) return false;
  }
  return true;
}
// A settings row fits the member it fills, and no two rows fill the same
// member (the same getter on the same axis and slot).
constexpr bool settings_fit_members() {
  using K = SettingAccess::Kind;
  for (const Register& r : kAll) {
    const SettingAccess& f = r.setting;
    if (!f.bound()) continue;
    if (f.per_axis != r.per_axis()) return false;
    if (f.elements == 0 ? r.slot != 0 : r.slot >= f.elements) return false;
    if (f.kind == K::flag && (r.min != 0 || r.max != 1)) return false;
    if (f.kind == K::integer && (r.min < 0 || r.max > f.max_raw)) return false;
    if (f.kind == K::enumeration && (r.type != Type::enumeration || r.min != 0 || r.max != f.max_raw))
      return false;
  }
  return true;
}
constexpr bool one_row_per_member() {
  // Settings rows only, so the pairwise pass stays within the compilers'
  // constant-evaluation step limits.
  std::array<const Register*, kAll.size()> rows{};
  std::size_t n = 0;
  for (const Register& r : kAll)
    if (r.setting.bound()) rows[n++] = &r;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      if (rows[i]->axis == rows[j]->axis && rows[i]->slot == rows[j]->slot &&
          rows[i]->setting.member == rows[j]->setting.member)
        return false;
  return true;
}
constexpr bool value_lists_named() {
  for (const Register& r : kAll) {
    if (r.values.empty()) continue;
    bool named = false;
    for (const ValueList& l : kValueLists) named |= l.values.data() == r.values.data();
    if (!named) return false;
  }
  return true;
}
static_assert(addresses_unique_without_overlap(), "two registers share an address in one (unit, table)");
static_assert(ranges_fit_types(), "a min, max or default does not fit its type or range");
static_assert(blocks_fit_strides(), "a per-axis row exceeds the stride, or a global reaches the axis blocks");
static_assert(kinds_consistent(), "table/type/access/persisted/values of a row do not agree");
static_assert(settings_fit_members(), "a settings row's range, type, axis or slot does not fit the member it fills");
static_assert(one_row_per_member(), "two rows fill the same setting");
static_assert(value_lists_named(), "a row's value list is missing from kValueLists");

}  // namespace

std::span<const Register> all_registers() { return kAll; }

std::span<const ValueList> value_lists() { return kValueLists; }

std::span<const Register> registers_of(Unit unit) {
  const auto first = std::find_if(kAll.begin(), kAll.end(), [&](const Register& r) { return r.unit == unit; });
  const auto last = std::find_if(first, kAll.end(), [&](const Register& r) { return r.unit != unit; });
  return {first, last};
}

std::string Register::name() const {
  std::string n(pattern);
  if (const auto at = n.find("<a>"); at != std::string::npos && axis >= 0)
    n.replace(at, 3, homing::kAxisLetters[static_cast<std::size_t>(axis)]);
  return n;
}

AxisKinds default_kinds() {
  AxisKinds k{};
  for (std::size_t a = 0; a < kAxisCount; ++a) k[a] = homing::default_kind(a);
  return k;
}

AxisKinds kinds_of(const homing::Settings& settings) {
  AxisKinds k{};
  for (std::size_t a = 0; a < kAxisCount; ++a) k[a] = homing::axis_kind(settings, a);
  return k;
}

std::string_view Register::unit_text() const { return unit_text(default_kinds()); }

std::string_view Register::unit_text(const AxisKinds& kinds) const {
  // A simulator axis is the machine's axis of the same letter.
  const bool rotary = axis >= 0 && kinds[static_cast<std::size_t>(axis)] == homing::AxisKind::rotary;
  switch (quantity) {
    case Quantity::none: return "";
    case Quantity::length_um: return rotary ? "deg" : "mm";
    case Quantity::velocity_um_per_s: return rotary ? "deg/s" : "mm/s";
    case Quantity::feedrate_per_min: return rotary ? "deg/min" : "mm/min";
    case Quantity::acceleration_per_s2: return rotary ? "deg/s²" : "mm/s²";
    case Quantity::time_ms: return "ms";
    case Quantity::time_s: return "s";
  }
  return "";
}

double Register::scale() const {
  return quantity == Quantity::length_um || quantity == Quantity::velocity_um_per_s ? 0.001 : 1.0;
}

std::string_view table_name(Table t) {
  switch (t) {
    case Table::coil: return "coil";
    case Table::discrete_input: return "discrete_input";
    case Table::input_register: return "input_register";
    case Table::holding_register: return "holding_register";
  }
  return "?";
}

std::string_view type_name(Type t) {
  switch (t) {
    case Type::boolean: return "bool";
    case Type::u16: return "u16";
    case Type::i16: return "i16";
    case Type::u32: return "u32";
    case Type::i32: return "i32";
    case Type::enumeration: return "enum";
    case Type::bitmask: return "bitmask";
  }
  return "?";
}

std::string_view access_name(Access a) {
  switch (a) {
    case Access::r: return "r";
    case Access::rw: return "rw";
    case Access::w: return "w";
  }
  return "?";
}

std::string_view unit_name(Unit u) { return u == Unit::module ? "module" : "simulator"; }

std::string_view value_name(const Register& reg, std::int64_t raw) {
  for (const EnumValue& v : reg.values)
    if (v.value == raw) return v.name;
  return "";
}

}  // namespace registers
