#pragma once
// The codec: the only place where raw register integers become engineering
// values and back, and where each row is bound to the engine's structs.
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>

#include "homing/settings.hpp"
#include "homing/status.hpp"
#include "registers/errors.hpp"
#include "registers/table.hpp"

namespace registers {

// Order of the two words of a 32-bit value (a start-up option of the server).
enum class WordOrder : std::uint8_t { high_first, low_first };

// ---- raw integer <-> words on the wire ----
// `out` / `words` hold exactly reg.words() words.
void encode_words(const Register& reg, std::int64_t raw, WordOrder order, std::span<std::uint16_t> out);
std::int64_t decode_words(const Register& reg, std::span<const std::uint16_t> words, WordOrder order);

// ---- raw integer <-> engineering value (raw × scale) ----
double to_engineering(const Register& reg, std::int64_t raw);
// Rounded to the nearest raw step and saturated to the type's range (a status
// value too large for the register reads as the extreme, never wraps).
std::int64_t to_raw(const Register& reg, double value);

// ---- run-time values that are not settings ----
// Holding registers and coils the host writes that are not persisted.
struct HostRegisters {
  std::uint16_t heartbeat = 0;                     // host.heartbeat
  std::array<double, homing::kAxisCount> target_mm{};  // axis.<a>.target (axis unit)
  bool homing_permit = false;                      // host.homing_permit
  std::uint32_t unlock_code = 0;                   // security.unlock(32), as last written (reads 0)
  std::array<bool, homing::kAxisCount> jog_plus{};     // cmd.jog_plus.<a> held
  std::array<bool, homing::kAxisCount> jog_minus{};    // cmd.jog_minus.<a> held
};

// Status the runtime adds to the engine's (history summary, map version).
struct StatusExtras {
  std::uint16_t map_version = kMapVersion;
  std::array<double, homing::kAxisCount> correction_mean_mm{};
  std::array<double, homing::kAxisCount> correction_spread_mm{};
  // The health trend of the homing history (server/health_trend.hpp).
  std::array<homing::HealthWarning, homing::kAxisCount> health_warning{};
  bool settings_locked = false;
  // Diagnostics of the running daemon (diag.*).
  std::uint64_t loop_periods = 0;
  double late_p50_us = 0, late_p99_us = 0, late_p999_us = 0, late_max_us = 0;
  double engine_step_ns = 0;
  std::uint64_t rss_kb = 0;
  std::uint32_t tcp_clients = 0;
  // The last refused write (owned by the Modbus service, not the monitor).
  std::uint16_t refusal_count = 0;
  std::uint16_t last_refused_register = 0;
  std::uint16_t last_refused_write = 0;
  std::uint16_t last_refusal_reason = 0;
  // The unlock code's guard (owned by the Modbus service).
  std::uint16_t unlock_lockout_s = 0;
  std::uint16_t wrong_unlock_codes = 0;
  // The reading client's edit session (owned by the Modbus service, per request).
  std::uint16_t edit_state = 0;  // 0 none, 1 open, 2 expired
  std::uint16_t edit_staged = 0;
};

// ---- coils and command registers -> commands ----
enum class Command : std::uint8_t {
  home_all, home_axis, abort, reset_alarm, jog_plus, jog_minus, move, homing_permit, lock_settings,
  home_axes,  // cmd.home_axes: one cycle of the named axes
  unhome_axis,  // cmd.unhome.<a>: forget the axis's reference
  set_position,  // cmd.set_position.<a>: the unhomed axis's coordinate is axis.<a>.target where it stands
  refcheck_axis,  // cmd.refcheck.<a>: reference check after a restart
  measure_axis,   // cmd.measure.<a>: commissioning measurement of the axis's travel
};
struct CommandRequest {
  Command command = Command::home_all;
  int axis = -1;     // 0..5 for per-axis commands, -1 otherwise
  bool on = true;    // jog / permit: the held state written; others: always true
  homing::AxisMask axes = 0;  // home_axes: the axes named (bit 0 = X)
  friend bool operator==(const CommandRequest&, const CommandRequest&) = default;
};
// The command a write of `raw` to a module coil or command register triggers
// (nullopt for rows that command nothing).
std::optional<CommandRequest> command_of(const Register& reg, std::int64_t raw);

// ---- bindings of module rows ----
// Holding rows bound to homing::Settings (persisted rows).
std::int64_t setting_raw(const homing::Settings& settings, const Register& reg);
void set_setting_raw(homing::Settings& settings, const Register& reg, std::int64_t raw);
// Non-persisted holding rows and host coils bound to HostRegisters.
std::int64_t host_raw(const HostRegisters& host, const Register& reg);
void set_host_raw(HostRegisters& host, const Register& reg, std::int64_t raw);

// Everything a read of the module unit can show.
struct ModuleView {
  const homing::Settings& settings;
  const HostRegisters& host;
  const homing::Status& status;
  const StatusExtras& extras;
};
// Raw value of any module register (coil commands read 0).
std::int64_t read_raw(const Register& reg, const ModuleView& view);

// ---- reading a range, as FC 1/2/3/4 ask ----
using RawReader = std::function<std::int64_t(const Register&)>;
// Fills out.size() words from `start`. Unmapped addresses inside the range
// read 0 (HMIs read whole blocks); a range with no register at all, or one
// running past 65535, is exception 02. A read may cover one half of a 32-bit value.
std::optional<Refusal> read_words(Unit unit, Table table, std::uint16_t start, std::span<std::uint16_t> out,
                                  WordOrder order, const RawReader& raw_of);
// Same for coils and discrete inputs; out[i] is 0 or 1.
std::optional<Refusal> read_bits(Unit unit, Table table, std::uint16_t start, std::span<std::uint8_t> out,
                                 const RawReader& raw_of);
// The module unit, straight from its view.
std::optional<Refusal> read_module_words(Table table, std::uint16_t start, std::span<std::uint16_t> out,
                                         WordOrder order, const ModuleView& view);
std::optional<Refusal> read_module_bits(Table table, std::uint16_t start, std::span<std::uint8_t> out,
                                        const ModuleView& view);

// "40101" style reference of an address, for messages (1-based, 6 digits).
std::string modbus_reference(Table table, std::uint16_t address);
// "axis.x.seek_feedrate = 1200 mm/min" style value text.
std::string format_value(const Register& reg, std::int64_t raw, const AxisKinds& kinds = default_kinds());

}  // namespace registers
