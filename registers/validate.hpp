#pragma once
// Validation of Modbus writes, all or nothing: the whole request is checked on
// a copy first (address, access, 32-bit halves, range, then the engine's own
// configuration check), and the caller applies the copy only when accepted.
#include <cstdint>
#include <expected>
#include <map>
#include <optional>
#include <string>
#include <span>
#include <vector>

#include "homing/settings.hpp"
#include "homing/status.hpp"
#include "registers/codec.hpp"
#include "registers/errors.hpp"
#include "registers/table.hpp"

namespace registers {

// One register of a request, decoded and range-checked.
struct RawWrite {
  const Register* reg = nullptr;
  std::int64_t raw = 0;
};

// One value that the request changes (only registers whose value differs).
struct Change {
  const Register* reg = nullptr;
  std::int64_t old_raw = 0;
  std::int64_t new_raw = 0;
};

// Address, access, 32-bit halves and range of a write to any unit. `values`
// are the words of FC 6/16/23, or one 0/1 per coil of FC 5/15. Answers
// 02 for an unmapped address anywhere in the range, a read-only register or
// table, or a write covering only one half of a 32-bit value; 03 for a value
// outside its range (address faults are reported first, as libmodbus does).
// `kinds` name the units in the messages (kinds_of the module's settings).
std::expected<std::vector<RawWrite>, Refusal> decode_write(Unit unit, Table table, std::uint16_t start,
                                                            std::span<const std::uint16_t> values,
                                                            WordOrder order,
                                                            const AxisKinds& kinds = default_kinds());

struct AcceptedWrite {
  std::vector<Change> changes;          // in address order
  homing::Settings settings;            // current settings with the whole request applied
  HostRegisters host;                   // current host values with the request applied
  std::vector<CommandRequest> commands; // coil writes that command something
  // True when a persisted setting changes: store `settings` before answering.
  bool changes_persisted() const;
};

// A write to the module unit (holding registers or coils). After the ranges,
// the request is applied to a copy and homing::check_axis runs for every axis
// the request touches whose mode is not disabled (and for slaves of a touched
// master that passed before): a fault is 03 with describe_fault()'s text.
// A cmd.home_axes mask that names no axis, or a disabled one, is 03.
// Not decided here: exception 06 while a homing cycle runs (the runtime knows).
std::expected<AcceptedWrite, Refusal> validate_write(Table table, std::uint16_t start,
                                                     std::span<const std::uint16_t> values, WordOrder order,
                                                     const homing::Settings& settings,
                                                     const HostRegisters& host);

// The same for writes already decoded and range-checked (decode_write), in
// address order: an edit session's staged settings at its commit.
std::expected<AcceptedWrite, Refusal> validate_raw_writes(std::span<const RawWrite> writes,
                                                          const homing::Settings& settings,
                                                          const HostRegisters& host);

// An accepted write whose command register the module cannot carry out now,
// judged on the published status (homing::homing_refusal_of) before anything
// of the write is applied: 06 while a homing cycle or a motion runs, 04 while
// an alarm, the e-stop, a drive fault, a lost link or a missing permit blocks
// homing. Coils are not judged here: their refusal is
// status.last_command_result, as the map promises.
std::optional<Refusal> refusal_now(const AcceptedWrite& write, const homing::Status& status);

// A whole set of settings by register name (an imported file, merged with the
// current settings): every name must be a persisted register, every value in
// its range, and every axis that homes must pass the engine's check, exactly
// as a Modbus write would. Returns the refusal naming the register, or nothing.
std::optional<Refusal> validate_settings_map(const std::map<std::string, std::int64_t>& settings);

}  // namespace registers
