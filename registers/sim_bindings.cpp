#include "registers/sim_bindings.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "registers/lookup.hpp"

namespace registers {
namespace {

using homing::sim::AxisConfig;
using homing::sim::MachineConfig;

// Every knob held as a double, in engineering units.
template <class A>
auto length_field(A& a, Key k) -> decltype(&a.noise_mm) {
  switch (k) {
    case Key::sim_actual_position: return &a.actual_position_mm;
    case Key::sim_sensor_min: return &a.sensor_min_mm;
    case Key::sim_sensor_max: return &a.sensor_max_mm;
    case Key::sim_hysteresis: return &a.hysteresis_mm;
    case Key::sim_noise: return &a.noise_mm;
    case Key::sim_bounce_ms: return &a.bounce_ms;
    case Key::sim_hard_stop_min: return &a.hard_stop_min_mm;
    case Key::sim_hard_stop_max: return &a.hard_stop_max_mm;
    case Key::sim_index_pitch: return &a.index_pitch_mm;
    case Key::sim_index_offset: return &a.index_offset_mm;
    case Key::sim_absolute_offset: return &a.absolute_offset_mm;
    case Key::sim_drive_home_position: return &a.drive_home_position_mm;
    case Key::sim_drive_speed: return &a.drive_speed_mm_per_min;
    case Key::sim_drive_answer_ms: return &a.drive_answer_ms;
    case Key::sim_unlock_delay_ms: return &a.unlock_delay_ms;
    case Key::sim_lock_delay_ms: return &a.lock_delay_ms;
    case Key::sim_limit_min: return &a.limit_min_mm;
    case Key::sim_limit_max: return &a.limit_max_mm;
    default: return nullptr;
  }
}

[[noreturn]] void unbound(const Register& reg) {
  throw std::logic_error(fmt::format("register {} has no simulator binding", reg.name()));
}

// Configuration rows (not readback, not lose_steps) into the config.
void set_config_raw(MachineConfig& config, SimSwitches& switches, const Register& reg, std::int64_t raw) {
  if (reg.per_axis()) {
    AxisConfig& a = config.axes[static_cast<std::size_t>(reg.axis)];
    if (double* d = length_field(a, reg.key)) {
      *d = to_engineering(reg, raw);
      return;
    }
    switch (reg.key) {
      case Key::sim_sensor_nc: a.sensor_nc = raw != 0; return;
      case Key::sim_limits_nc: a.limits_nc = raw != 0; return;
      case Key::sim_fault: a.fault = static_cast<homing::sim::Fault>(raw); return;
      case Key::sim_lose_steps: return;  // an action, not a setting
      default: unbound(reg);
    }
  }
  switch (reg.key) {
    case Key::sim_seed: config.seed = static_cast<std::uint64_t>(raw); return;
    case Key::sim_estop: switches.estop = raw != 0; return;
    case Key::sim_start_button: switches.start_button = raw != 0; return;
    default: unbound(reg);
  }
}

}  // namespace

MachineConfig default_sim_config() {
  MachineConfig c;
  SimSwitches s;
  for (const Register& r : registers_of(Unit::simulator))
    if (r.writable()) set_config_raw(c, s, r, r.default_raw);
  return c;
}

SimSwitches default_sim_switches() {
  MachineConfig c;
  SimSwitches s;
  for (const Register& r : registers_of(Unit::simulator))
    if (r.table == Table::coil) set_config_raw(c, s, r, r.default_raw);
  return s;
}

std::int64_t sim_raw(const Register& reg, const MachineConfig& config, const SimSwitches& switches,
                     const SimReadback& readback) {
  if (reg.per_axis()) {
    const auto i = static_cast<std::size_t>(reg.axis);
    const AxisConfig& a = config.axes[i];
    switch (reg.key) {
      case Key::sim_actual_position: return to_raw(reg, readback.actual_position_mm[i]);
      case Key::sim_sensor: return readback.sensor[i] ? 1 : 0;
      case Key::sim_at_hard_stop: return readback.at_hard_stop[i] ? 1 : 0;
      case Key::sim_driven_by: return readback.driven_by[i];
      case Key::sim_indexer_locked: return readback.indexer_locked[i] ? 1 : 0;
      case Key::sim_lose_steps: return 0;
      case Key::sim_sensor_nc: return a.sensor_nc ? 1 : 0;
      case Key::sim_limits_nc: return a.limits_nc ? 1 : 0;
      case Key::sim_limit_min_active: return readback.limit_min[i] ? 1 : 0;
      case Key::sim_limit_max_active: return readback.limit_max[i] ? 1 : 0;
      case Key::sim_fault: return static_cast<std::int64_t>(a.fault);
      default: break;
    }
    if (const double* d = length_field(a, reg.key)) return to_raw(reg, *d);
    unbound(reg);
  }
  switch (reg.key) {
    case Key::sim_seed: return static_cast<std::int64_t>(config.seed & 0xFFFF'FFFFu);
    case Key::sim_estop: return switches.estop ? 1 : 0;
    case Key::sim_start_button: return switches.start_button ? 1 : 0;
    default: unbound(reg);
  }
}

bool moves_geometry(Key key) {
  switch (key) {
    case Key::sim_actual_position:
    case Key::sim_sensor_min:
    case Key::sim_sensor_max:
    case Key::sim_hard_stop_min:
    case Key::sim_hard_stop_max:
    case Key::sim_index_pitch:
    case Key::sim_index_offset:
    case Key::sim_absolute_offset:
    case Key::sim_drive_home_position: return true;
    default: return false;
  }
}

std::expected<AcceptedSimWrite, Refusal> validate_sim_write(Table table, std::uint16_t start,
                                                            std::span<const std::uint16_t> values,
                                                            WordOrder order, const MachineConfig& config,
                                                            const SimSwitches& switches,
                                                            const SimReadback& readback) {
  auto decoded = decode_write(Unit::simulator, table, start, values, order);
  if (!decoded) return std::unexpected(decoded.error());
  AcceptedSimWrite out{{}, config, switches, {}, {}, {}, false};
  for (const RawWrite& w : *decoded) {
    const Register& reg = *w.reg;
    const std::int64_t old_raw = sim_raw(reg, out.config, out.switches, readback);
    set_config_raw(out.config, out.switches, reg, w.raw);
    if (reg.per_axis()) {
      const auto i = static_cast<std::size_t>(reg.axis);
      out.axes_written[i] = true;
      // The carriage's own value written back unchanged (a block write of
      // its stops) places nothing: only a stop moved onto it pushes it along.
      if (reg.key == Key::sim_actual_position && w.raw != old_raw) out.placed[i] = true;
      if (reg.key == Key::sim_lose_steps) out.lose_steps_mm[i] = to_engineering(reg, w.raw);
    }
    if (reg.key == Key::sim_seed) out.seed_written = true;
    if (old_raw != w.raw || reg.key == Key::sim_lose_steps) out.changes.push_back({&reg, old_raw, w.raw});
  }
  for (std::size_t i = 0; i < homing::kAxisCount; ++i) {
    const AxisConfig& a = out.config.axes[i];
    if (a.hard_stop_min_mm >= a.hard_stop_max_mm) {
      const Register* min_reg = find_register(fmt::format("sim.{}.hard_stop_min", homing::kAxisLetters[i]));
      return std::unexpected(Refusal::because(
          RefusalReason::hard_stops_inverted, min_reg ? min_reg->address : start,
          fmt::format("sim.{0}.hard_stop_min ({1}) must be below sim.{0}.hard_stop_max ({2}); nothing was written",
                      homing::kAxisLetters[i], a.hard_stop_min_mm, a.hard_stop_max_mm)));
    }
    // Moving a stop onto the carriage pushes it along, as a real stop would;
    // placing the carriage beyond one would be a silent clamp.
    if (out.placed[i] && (a.actual_position_mm < a.hard_stop_min_mm || a.actual_position_mm > a.hard_stop_max_mm)) {
      const Register* reg = find_register(fmt::format("sim.{}.actual_position", homing::kAxisLetters[i]));
      return std::unexpected(Refusal::because(
          RefusalReason::beyond_hard_stop, reg ? reg->address : start,
          fmt::format("sim.{0}.actual_position ({1}) is beyond the carriage's hard stops ({2} to {3}): place it "
                      "between them or move a stop in the same request; nothing was written",
                      homing::kAxisLetters[i], a.actual_position_mm, a.hard_stop_min_mm, a.hard_stop_max_mm)));
    }
  }
  return out;
}

}  // namespace registers
