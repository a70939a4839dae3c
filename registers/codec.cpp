// Raw <-> engineering conversion and the binding of every row to the engine's
// structs. Settings rows carry the member they fill; every other row has one
// case per Key. A row without a binding is a table bug and throws (the tests
// touch every row, so it cannot ship).
#include "registers/codec.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "registers/lookup.hpp"

namespace registers {
namespace {

using homing::Settings;

[[noreturn]] void unbound(const Register& reg, std::string_view what) {
  throw std::logic_error(fmt::format("register {} has no {} binding", reg.name(), what));
}

// Exact divisor of the scale: dividing by 1000 (not multiplying by 0.001)
// gives the double nearest to the decimal value, so 100 µm prints as 0.1.
double divisor(const Register& reg) { return reg.scale() == 1.0 ? 1.0 : std::round(1.0 / reg.scale()); }

template <class E>
std::int64_t raw_of(E e) { return static_cast<std::int64_t>(e); }

std::size_t axis_index(const Register& reg) { return static_cast<std::size_t>(reg.axis); }

}  // namespace

// ---- words ----
void encode_words(const Register& reg, std::int64_t raw, WordOrder order, std::span<std::uint16_t> out) {
  const auto u = static_cast<std::uint32_t>(static_cast<std::uint64_t>(raw) & 0xFFFF'FFFFu);
  if (reg.words() == 1) {
    out[0] = static_cast<std::uint16_t>(u & 0xFFFFu);
    return;
  }
  const auto hi = static_cast<std::uint16_t>(u >> 16);
  const auto lo = static_cast<std::uint16_t>(u & 0xFFFFu);
  out[0] = order == WordOrder::high_first ? hi : lo;
  out[1] = order == WordOrder::high_first ? lo : hi;
}

std::int64_t decode_words(const Register& reg, std::span<const std::uint16_t> words, WordOrder order) {
  if (reg.words() == 1) {
    if (reg.type == Type::i16) return static_cast<std::int16_t>(words[0]);
    return words[0];
  }
  const std::uint32_t hi = order == WordOrder::high_first ? words[0] : words[1];
  const std::uint32_t lo = order == WordOrder::high_first ? words[1] : words[0];
  const std::uint32_t u = (hi << 16) | lo;
  if (reg.type == Type::i32) return static_cast<std::int32_t>(u);
  return u;
}

// ---- scale ----
double to_engineering(const Register& reg, std::int64_t raw) {
  return static_cast<double>(raw) / divisor(reg);
}

std::int64_t to_raw(const Register& reg, double value) {
  if (std::isnan(value)) return 0;
  const double scaled = std::round(value * divisor(reg));
  const auto lo = static_cast<double>(type_min(reg.type));
  const auto hi = static_cast<double>(type_max(reg.type));
  return static_cast<std::int64_t>(std::clamp(scaled, lo, hi));
}

// ---- commands ----
std::optional<CommandRequest> command_of(const Register& reg, std::int64_t raw) {
  if (reg.unit != Unit::module) return std::nullopt;
  if (reg.table == Table::holding_register) {
    if (reg.key != Key::cmd_home_axes) return std::nullopt;
    return CommandRequest{Command::home_axes, -1, true, static_cast<homing::AxisMask>(raw & homing::kAllAxes)};
  }
  if (reg.table != Table::coil) return std::nullopt;
  const Register& coil = reg;
  const bool value = raw != 0;
  const int axis = coil.axis;
  switch (coil.key) {
    case Key::cmd_home_all: return CommandRequest{Command::home_all, -1, true};
    case Key::cmd_abort: return CommandRequest{Command::abort, -1, true};
    case Key::cmd_reset_alarm: return CommandRequest{Command::reset_alarm, -1, true};
    case Key::cmd_home: return CommandRequest{Command::home_axis, axis, true};
    case Key::cmd_unhome: return CommandRequest{Command::unhome_axis, axis, true};
    case Key::cmd_refcheck: return CommandRequest{Command::refcheck_axis, axis, true};
    case Key::cmd_measure: return CommandRequest{Command::measure_axis, axis, true};
    case Key::cmd_move: return CommandRequest{Command::move, axis, true};
    case Key::cmd_set_position: return CommandRequest{Command::set_position, axis, true};
    case Key::cmd_jog_plus: return CommandRequest{Command::jog_plus, axis, value};
    case Key::cmd_jog_minus: return CommandRequest{Command::jog_minus, axis, value};
    case Key::host_homing_permit: return CommandRequest{Command::homing_permit, -1, value};
    case Key::cmd_lock_settings: return CommandRequest{Command::lock_settings, -1, true};
    default: unbound(coil, "command");
  }
}

// ---- settings ----
// Each settings row carries the member it fills (registers/fills.hpp).
std::int64_t setting_raw(const Settings& settings, const Register& reg) {
  if (!reg.setting.bound()) unbound(reg, "settings");
  return reg.setting.get(settings, reg);
}

void set_setting_raw(Settings& settings, const Register& reg, std::int64_t raw) {
  if (!reg.setting.bound()) unbound(reg, "settings");
  reg.setting.set(settings, reg, raw);
}

// ---- host values ----
std::int64_t host_raw(const HostRegisters& host, const Register& reg) {
  switch (reg.key) {
    case Key::host_heartbeat: return host.heartbeat;
    case Key::host_target: return to_raw(reg, host.target_mm.at(axis_index(reg)));
    case Key::host_homing_permit: return host.homing_permit ? 1 : 0;
    case Key::security_unlock: return 0;  // a code is never read back
    case Key::cmd_home_axes: return 0;    // a command: it holds nothing
    case Key::edit_command: return 0;     // a command: it holds nothing
    case Key::cmd_jog_plus: return host.jog_plus.at(axis_index(reg)) ? 1 : 0;
    case Key::cmd_jog_minus: return host.jog_minus.at(axis_index(reg)) ? 1 : 0;
    default: unbound(reg, "host");
  }
}

void set_host_raw(HostRegisters& host, const Register& reg, std::int64_t raw) {
  switch (reg.key) {
    case Key::host_heartbeat: host.heartbeat = static_cast<std::uint16_t>(raw); return;
    case Key::host_target: host.target_mm.at(axis_index(reg)) = to_engineering(reg, raw); return;
    case Key::host_homing_permit: host.homing_permit = raw != 0; return;
    case Key::security_unlock: host.unlock_code = static_cast<std::uint32_t>(raw); return;
    case Key::cmd_home_axes: return;  // a command (validate_write), nothing held
    case Key::edit_command: return;   // the Modbus service's edit sessions, nothing held
    // Read back who holds them (server/jog_buttons.hpp), not the last value written.
    case Key::cmd_jog_plus:
    case Key::cmd_jog_minus: return;
    default: unbound(reg, "host");
  }
}

// ---- status ----
std::int64_t read_raw(const Register& reg, const ModuleView& view) {
  if (reg.unit != Unit::module) unbound(reg, "module read");
  const homing::Status& st = view.status;
  if (reg.table == Table::holding_register)
    return reg.persisted ? setting_raw(view.settings, reg) : host_raw(view.host, reg);
  if (reg.table == Table::coil) {
    const bool held = reg.key == Key::host_homing_permit || reg.key == Key::cmd_jog_plus ||
                      reg.key == Key::cmd_jog_minus;
    return held ? host_raw(view.host, reg) : 0;  // pulse commands read back 0
  }
  if (reg.per_axis()) {
    const std::size_t i = axis_index(reg);
    const homing::AxisStatus& a = st.axes[i];
    switch (reg.key) {
      case Key::axis_phase: return raw_of(a.phase);
      case Key::axis_alarm: return raw_of(a.alarm.code);
      case Key::axis_alarm_phase: return a.alarm ? raw_of(a.alarm.phase) : 0;
      case Key::axis_alarm_value: return a.alarm ? to_raw(reg, a.alarm.value) : 0;
      case Key::axis_alarm_side: return a.alarm ? raw_of(a.alarm.side) : 0;
      case Key::axis_alarm_rule: return a.alarm ? a.alarm.rule : 0;
      case Key::axis_alarm_rack_at_start: return a.alarm ? to_raw(reg, a.alarm.rack_at_start_mm) : 0;
      case Key::axis_position: return to_raw(reg, a.position_mm);
      case Key::axis_velocity: return to_raw(reg, a.velocity_mm_per_s);
      case Key::axis_home_correction: return to_raw(reg, a.home_correction_mm);
      case Key::axis_stop_distance: return to_raw(reg, a.stop_distance_mm);
      case Key::axis_trigger_position: return to_raw(reg, a.trigger_position_mm);
      case Key::axis_phase_distance: return to_raw(reg, a.phase_distance_mm);
      case Key::axis_correction_mean: return to_raw(reg, view.extras.correction_mean_mm[i]);
      case Key::axis_correction_spread: return to_raw(reg, view.extras.correction_spread_mm[i]);
      case Key::axis_latch_spread: return to_raw(reg, a.health.latch_spread_mm);
      case Key::axis_latch_sigma: return to_raw(reg, a.health.latch_sigma_mm);
      case Key::axis_latch_passes_done: return a.health.latch_passes;
      case Key::axis_hysteresis: return to_raw(reg, a.health.hysteresis_mm);
      case Key::axis_seek_latch_difference: return to_raw(reg, a.health.seek_latch_mm);
      case Key::axis_chatter_edges: return std::min(a.health.chatter_edges, 65535);
      case Key::axis_index_distance: return to_raw(reg, a.health.index_distance_mm);
      case Key::axis_index_near_edge: return a.health.index_near_edge ? 1 : 0;
      case Key::axis_gantry_skew: return a.health.gantry_skew_measured ? to_raw(reg, a.health.gantry_skew_mm) : 0;
      case Key::axis_health_warning: return raw_of(view.extras.health_warning[i]);
      case Key::axis_trust: return raw_of(a.trust);
      case Key::axis_refcheck_error: return to_raw(reg, a.refcheck_error_mm);
      case Key::axis_measured_travel: return to_raw(reg, a.measurement.usable_travel_mm);
      case Key::axis_measured_soft_limit_min: return to_raw(reg, a.measurement.soft_limit_min_mm);
      case Key::axis_measured_soft_limit_max: return to_raw(reg, a.measurement.soft_limit_max_mm);
      case Key::axis_measured_max_seek_travel: return to_raw(reg, a.measurement.max_seek_travel_mm);
      case Key::axis_homed: return a.homed ? 1 : 0;
      case Key::axis_sensor: return a.sensor ? 1 : 0;
      case Key::axis_busy: return a.busy ? 1 : 0;
      case Key::axis_limit_min: return a.limit_min ? 1 : 0;
      case Key::axis_limit_max: return a.limit_max ? 1 : 0;
      default: unbound(reg, "status");
    }
  }
  switch (reg.key) {
    case Key::status_map_version: return view.extras.map_version;
    case Key::status_state: return raw_of(st.state);
    case Key::status_sequence_step: return st.sequence_step;
    case Key::status_homing_cycles: return st.homing_cycles;
    case Key::status_heartbeat: return st.heartbeat & 0xFFFFu;  // wraps: a watchdog only needs change
    case Key::status_last_command_result: return raw_of(st.last_command_result);
    case Key::status_interlocks: return st.interlocks;
    case Key::status_global_alarm: return raw_of(st.global_alarm);
    case Key::status_alarm_axis: return homing::reported_alarm_axis(st) + 1;
    case Key::status_settings_locked: return view.extras.settings_locked ? 1 : 0;
    case Key::status_command_count: return st.command_count & 0xFFFFu;
    case Key::diag_loop_periods: return static_cast<std::int64_t>(view.extras.loop_periods & 0xFFFFFFFFu);
    case Key::diag_late_p50_us: return to_raw(reg, view.extras.late_p50_us);
    case Key::diag_late_p99_us: return to_raw(reg, view.extras.late_p99_us);
    case Key::diag_late_p999_us: return to_raw(reg, view.extras.late_p999_us);
    case Key::diag_late_max_us: return to_raw(reg, view.extras.late_max_us);
    case Key::diag_engine_step_ns: return to_raw(reg, view.extras.engine_step_ns);
    case Key::diag_rss_kb: return static_cast<std::int64_t>(std::min<std::uint64_t>(view.extras.rss_kb, 0xFFFFFFFFu));
    case Key::diag_tcp_clients: return view.extras.tcp_clients;
    case Key::status_refusal_count: return view.extras.refusal_count;
    case Key::status_last_refused_register: return view.extras.last_refused_register;
    case Key::status_last_refused_write: return view.extras.last_refused_write;
    case Key::status_last_refusal_reason: return view.extras.last_refusal_reason;
    case Key::status_unlock_lockout_s: return view.extras.unlock_lockout_s;
    case Key::status_wrong_unlock_codes: return view.extras.wrong_unlock_codes;
    case Key::edit_state: return view.extras.edit_state;
    case Key::edit_staged: return view.extras.edit_staged;
    case Key::status_alarm: return st.alarm ? 1 : 0;
    case Key::status_homing: return st.homing ? 1 : 0;
    case Key::status_estop: return st.estop ? 1 : 0;
    default: unbound(reg, "status");
  }
}

// ---- ranges ----
namespace {
std::optional<Refusal> check_read_range(Unit unit, Table table, std::uint16_t start, std::size_t count) {
  if (count == 0) return Refusal{ExceptionCode::illegal_data_value, "a read of 0 items"};
  if (std::size_t{start} + count > 65536)
    return Refusal{ExceptionCode::illegal_data_address,
                   fmt::format("{} {}..{} runs past address 65535", table_name(table), start,
                               std::size_t{start} + count - 1)};
  if (!registers_overlapping(unit, table, start, count).empty()) return std::nullopt;
  return Refusal{ExceptionCode::illegal_data_address,
                 fmt::format("no {} of the {} unit is mapped at {}..{} (see hmi_maps/)", table_name(table),
                             unit_name(unit), start, std::size_t{start} + count - 1)};
}
}  // namespace

std::optional<Refusal> read_words(Unit unit, Table table, std::uint16_t start, std::span<std::uint16_t> out,
                                  WordOrder order, const RawReader& raw_of) {
  if (auto bad = check_read_range(unit, table, start, out.size())) return bad;
  std::fill(out.begin(), out.end(), 0);  // gaps in the map read 0
  for (const Register& reg : registers_overlapping(unit, table, start, out.size())) {
    std::array<std::uint16_t, 2> w{};
    encode_words(reg, raw_of(reg), order, std::span(w).first(reg.words()));
    for (std::size_t k = 0; k < reg.words(); ++k) {
      const std::size_t address = std::size_t{reg.address} + k;
      if (address >= start && address - start < out.size()) out[address - start] = w[k];
    }
  }
  return std::nullopt;
}

std::optional<Refusal> read_bits(Unit unit, Table table, std::uint16_t start, std::span<std::uint8_t> out,
                                 const RawReader& raw_of) {
  if (auto bad = check_read_range(unit, table, start, out.size())) return bad;
  std::fill(out.begin(), out.end(), 0);
  for (const Register& reg : registers_overlapping(unit, table, start, out.size()))
    if (reg.address >= start) out[reg.address - start] = raw_of(reg) != 0 ? 1 : 0;  // a bit register is one address
  return std::nullopt;
}

std::optional<Refusal> read_module_words(Table table, std::uint16_t start, std::span<std::uint16_t> out,
                                         WordOrder order, const ModuleView& view) {
  return read_words(Unit::module, table, start, out, order,
                    [&](const Register& r) { return read_raw(r, view); });
}

std::optional<Refusal> read_module_bits(Table table, std::uint16_t start, std::span<std::uint8_t> out,
                                        const ModuleView& view) {
  return read_bits(Unit::module, table, start, out, [&](const Register& r) { return read_raw(r, view); });
}

// ---- text ----
std::string modbus_reference(Table table, std::uint16_t address) {
  const int prefix = table == Table::coil ? 0 : table == Table::discrete_input ? 1
                   : table == Table::input_register ? 3 : 4;
  return fmt::format("{}{:05d}", prefix, std::uint32_t{address} + 1);
}

std::string format_value(const Register& reg, std::int64_t raw, const AxisKinds& kinds) {
  if (reg.type == Type::enumeration) {
    const auto n = value_name(reg, raw);
    return n.empty() ? fmt::format("{}", raw) : fmt::format("{} ({})", raw, n);
  }
  const auto unit = reg.unit_text(kinds);
  if (unit.empty()) return fmt::format("{}", to_engineering(reg, raw));
  return fmt::format("{} {}", to_engineering(reg, raw), unit);
}

}  // namespace registers
