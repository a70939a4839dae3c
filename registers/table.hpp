#pragma once
// The one table of truth: the row type of every Modbus register of the module
// and of the simulator unit. The rows themselves live in table.cpp; the codec,
// the write validation, the defaults, the SQLite keys and every file in
// hmi_maps/ are derived from them. Numbers in a row are typed integers (raw
// register values), never strings, so the compiler checks them (see the
// static_asserts in table.cpp).
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "homing/axes.hpp"
#include "homing/settings.hpp"

namespace registers {

// Bump when a published address or meaning changes (status.map_version).
inline constexpr std::uint16_t kMapVersion = 1;

// Which Modbus unit (slave id) a register belongs to. The ids themselves are
// run-time options (--unit, default 1; --sim-unit, default 247).
enum class Unit : std::uint8_t { module = 0, simulator = 1 };
inline constexpr std::uint8_t kDefaultModuleUnitId = 1;
inline constexpr std::uint8_t kDefaultSimUnitId = 247;

// Enum order = the classic 0x/1x/3x/4x order, used to sort the exports.
enum class Table : std::uint8_t { coil = 0, discrete_input = 1, input_register = 2, holding_register = 3 };
enum class Type : std::uint8_t { boolean, u16, i16, u32, i32, enumeration, bitmask };
enum class Access : std::uint8_t { r, rw, w };

// What the raw integer measures. Together with the axis's kind (linear or rotary) it
// gives the unit text and the scale, so no row can pair µm with scale 1.
enum class Quantity : std::uint8_t {
  none,              // counts, codes, flags: scale 1, no unit
  length_um,         // raw µm (millidegree on rotary axes), scale 0.001, unit mm / deg
  velocity_um_per_s, // raw µm/s (millideg/s), scale 0.001, unit mm/s / deg/s
  feedrate_per_min,  // raw mm/min (deg/min), scale 1
  acceleration_per_s2,  // raw mm/s² (deg/s²), scale 1
  time_ms,           // raw milliseconds, scale 1
  time_s,            // raw seconds, scale 1
};

// What a register that is not a setting is bound to (status, host values,
// commands, the simulator unit): the codec has one case per key; the axis (or
// sequence step) comes from the row, so one key serves six rows. Settings rows
// have no key: they carry the member they fill (SettingAccess).
enum class Key : std::uint8_t {
  none,  // a settings row (see SettingAccess)
  // holding, module: host values
  host_heartbeat, host_target,
  // input registers, module
  status_map_version, status_state, status_sequence_step, status_homing_cycles, status_heartbeat,
  status_last_command_result, status_interlocks, status_global_alarm, status_alarm_axis,
  status_settings_locked, status_command_count, axis_alarm_value, diag_loop_periods, diag_late_p50_us, diag_late_p99_us, diag_late_p999_us,
  diag_late_max_us, diag_engine_step_ns, diag_rss_kb, diag_tcp_clients,
  status_refusal_count, status_last_refused_register, status_last_refusal_reason, status_last_refused_write,
  status_unlock_lockout_s, status_wrong_unlock_codes, edit_state, edit_staged,
  axis_phase, axis_alarm, axis_alarm_phase, axis_position, axis_velocity, axis_home_correction,
  axis_stop_distance, axis_trigger_position, axis_phase_distance, axis_correction_mean,
  axis_correction_spread, axis_latch_spread, axis_latch_sigma, axis_latch_passes_done,
  axis_hysteresis, axis_seek_latch_difference, axis_chatter_edges, axis_index_distance, axis_index_near_edge,
  axis_gantry_skew, axis_health_warning, axis_trust, axis_refcheck_error,
  axis_measured_travel, axis_measured_soft_limit_min, axis_measured_soft_limit_max, axis_measured_max_seek_travel,
  axis_alarm_side, axis_alarm_rack_at_start, axis_alarm_rule,
  // discrete inputs, module
  status_alarm, status_homing, status_estop, axis_homed, axis_sensor, axis_busy, axis_limit_min, axis_limit_max,
  // coils, module
  cmd_home_all, cmd_abort, cmd_reset_alarm, host_homing_permit, cmd_lock_settings, security_unlock,
  cmd_home, cmd_unhome, cmd_jog_plus,
  cmd_jog_minus, cmd_move, cmd_set_position, cmd_refcheck, cmd_measure,
  // holding, module: command registers (hold nothing, read 0)
  cmd_home_axes, edit_command,
  // simulator unit
  sim_seed, sim_actual_position, sim_sensor_min, sim_sensor_max, sim_hysteresis, sim_noise,
  sim_bounce_ms, sim_sensor_nc, sim_hard_stop_min, sim_hard_stop_max, sim_index_pitch,
  sim_index_offset, sim_absolute_offset, sim_fault, sim_lose_steps, sim_estop, sim_start_button,
  sim_sensor, sim_at_hard_stop, sim_driven_by,
  sim_drive_home_position, sim_drive_speed, sim_drive_answer_ms,
  sim_unlock_delay_ms, sim_lock_delay_ms, sim_indexer_locked,
  sim_limit_min, sim_limit_max, sim_limits_nc, sim_limit_min_active, sim_limit_max_active,
};

struct Register;

// The kind each axis moves with (homing::axis_kind: its axis.<a>.kind, a
// slave its master's). It names the unit of the axis's lengths, feedrates and
// accelerations: mm or deg. Texts made without settings (the committed
// hmi_maps/) use a new module's kinds.
using AxisKinds = std::array<homing::AxisKind, homing::kAxisCount>;
AxisKinds default_kinds();  // X Y Z linear, A B C rotary (the defaults of axis.<a>.kind)
AxisKinds kinds_of(const homing::Settings& settings);

// What a settings row fills: one member of homing::AxisSettings (per-axis rows;
// the row's axis picks the element of Settings::axes) or of
// homing::GlobalSettings (of an array member, the row's slot picks the
// element). Made from a pointer to the member by fills<&Member>
// (registers/fills.hpp): the getter and setter convert between the member and
// the raw register value with the row's scale, so no code anywhere names a
// setting one by one. A row that fills a setting is persisted; its SQLite key
// is its register name.
struct SettingAccess {
  enum class Kind : std::uint8_t { none, real, flag, integer, enumeration };
  Kind kind = Kind::none;
  bool per_axis = false;      // a member of AxisSettings, else of GlobalSettings
  std::uint8_t elements = 0;  // an array member: its size (a row fills element `slot`); else 0
  std::int64_t max_raw = 0;   // integers and enums: the largest value the member can hold
  // Names the member filled (the compiler's spelling of the member pointer):
  // two rows fill the same member exactly when these are equal. A text, because
  // GCC will not compare function or object addresses in constant expressions
  // under the sanitizers.
  std::string_view member;
  std::int64_t (*get)(const homing::Settings&, const Register&) = nullptr;
  void (*set)(homing::Settings&, const Register&, std::int64_t raw) = nullptr;
  constexpr bool bound() const { return kind != Kind::none; }
};

// One value of an enum register, or one bit of a bitmask register (value = bit number).
struct EnumValue {
  std::int64_t value = 0;
  std::string_view name;
  std::string_view meaning;
};

// A value list of the table under the name hmi_maps/enums.csv gives it.
struct ValueList {
  std::string_view name;
  std::span<const EnumValue> values;
};

// What the runtime does beyond applying a setting when a write changes it,
// declared on the setting's row so that no transport names a setting.
enum class Effect : std::uint8_t {
  none,
  history_limits,  // the audit log and the homing history are pruned to the new row count
};

// One register, expanded (per-axis rows already carry their axis and address).
struct Register {
  std::string_view pattern;  // "axis.<a>.mode": <a> becomes the axis letter
  Unit unit = Unit::module;
  Table table = Table::holding_register;
  std::uint16_t address = 0;  // 0-based protocol address (first word)
  Type type = Type::u16;
  Access access = Access::r;
  Quantity quantity = Quantity::none;
  std::int64_t min = 0;  // raw
  std::int64_t max = 0;  // raw
  std::int64_t default_raw = 0;
  bool persisted = false;   // a setting: it fills a member of homing::Settings
  SettingAccess setting{};  // bound when persisted
  Key key = Key::none;
  std::int8_t axis = -1;    // 0..5 for per-axis rows, -1 otherwise
  std::uint8_t slot = 0;    // sequence.step<slot+1>
  std::uint8_t offset = 0;  // offset inside the per-axis block (per-axis rows)
  std::span<const EnumValue> values{};  // enum values / bitmask bits
  std::string_view description;
  Effect effect = Effect::none;  // settings rows: what else a change of it does

  constexpr std::uint16_t words() const { return type == Type::u32 || type == Type::i32 ? 2 : 1; }
  constexpr bool per_axis() const { return axis >= 0; }
  constexpr bool writable() const { return access != Access::r; }
  constexpr std::uint32_t end() const { return std::uint32_t{address} + words(); }  // one past
  std::string name() const;
  // "mm", "deg/min", "" ...: the unit on an axis of the kind it moves with.
  std::string_view unit_text(const AxisKinds& kinds) const;
  std::string_view unit_text() const;  // with default_kinds(): only where no settings are known
  double scale() const;                // engineering = raw * scale
};

// Per-axis blocks: register of axis i = base + stride * i + offset. Globals sit below base.
struct AxisBlock {
  std::uint16_t base = 0;
  std::uint16_t stride = 0;
};
constexpr AxisBlock axis_block(Table table) {
  return table == Table::holding_register || table == Table::input_register ? AxisBlock{100, 100}
                                                                           : AxisBlock{100, 10};
}

// Every register of both units, sorted by (unit, table, address).
std::span<const Register> all_registers();
std::span<const Register> registers_of(Unit unit);

// Raw range that each type can carry on the wire.
constexpr std::int64_t type_min(Type t) {
  switch (t) {
    case Type::i16: return -32768;
    case Type::i32: return -2147483648LL;
    default: return 0;
  }
}
constexpr std::int64_t type_max(Type t) {
  switch (t) {
    case Type::boolean: return 1;
    case Type::i16: return 32767;
    case Type::u32: return 4294967295LL;
    case Type::i32: return 2147483647LL;
    default: return 65535;
  }
}

std::string_view table_name(Table t);  // "coil", "discrete_input", ...
std::string_view type_name(Type t);    // "bool", "u16", ... "enum", "bitmask"
std::string_view access_name(Access a);
std::string_view unit_name(Unit u);    // "module", "simulator"

// Every value list the registers use (enum values, bitmask bits), named; each
// register's `values` is one of them.
std::span<const ValueList> value_lists();

// Name of an enum value of a register ("" if not listed).
std::string_view value_name(const Register& reg, std::int64_t raw);

}  // namespace registers
