#pragma once
// Settings over Modbus: read them all, plan an all-or-nothing write of several
// values (validated locally with the daemon's own code first, so a refusal
// names the setting and the rule), execute it, and the export/import file
// (the same TOML as persistence's export_file / import_file, in engineering
// units with value names).
#include <cstdint>
#include <expected>
#include <map>
#include <string>
#include <vector>

#include "connection.hpp"
#include "homing/settings.hpp"
#include "registers/codec.hpp"

namespace homingctl {

using RawMap = std::map<std::string, std::int64_t>;

// Every persisted holding register of the module unit, in address order.
const std::vector<const registers::Register*>& persisted_registers();

RawMap read_settings_raw(Connection& c);
homing::Settings settings_of(const RawMap& raw);  // registers::settings_from_raw
homing::Settings read_settings(Connection& c);
// The kinds the module's axes move with, read only when a value of `regs`
// has a unit that depends on one (a length, feedrate ... of A, B or C);
// `changing`: settings a write sets at the same time (axis.a.kind = linear),
// taken as they will be.
registers::AxisKinds kinds_for(Connection& c, const std::vector<const registers::Register*>& regs,
                               const RawMap& changing = {});

struct Block {
  std::uint16_t start = 0;
  std::vector<std::uint16_t> words;  // new words
};
struct PlannedChange {
  const registers::Register* reg = nullptr;
  std::int64_t old_raw = 0;
  std::int64_t new_raw = 0;
};
struct WritePlan {
  std::vector<Block> blocks;  // staged in one edit session, checked together at its commit
  std::vector<PlannedChange> changes;
  registers::AxisKinds kinds = registers::default_kinds();  // after the write: the units of the changes
};

// Plans writing `wanted` (module holding registers, name -> raw) over `current`
// (raw values of at least every persisted register and every named one).
// Refused with a sentence naming the setting and the rule, exactly like the
// daemon would, when the final settings cannot work.
// With check = false the local checks are skipped (the daemon decides alone).
std::expected<WritePlan, std::string> plan_write(const RawMap& current, const RawMap& wanted,
                                                 registers::WordOrder order, bool check = true);

// Writes the plan's blocks in one edit session and commits it: the module
// applies all of them in one transaction or none. A refusal (of a block or
// at the commit) discards the session and says why (the module's refusal
// reason and the register it is about).
std::expected<void, std::string> execute_plan(Connection& c, const WritePlan& plan);

// Why the module refused the last write (of a holding register of `written`'s
// unit), from its refusal registers: the reason's text and the register it is about.
std::string refusal_reason(Connection& c, registers::Unit written);

// ---- the settings file (persistence/settings_file.hpp's format) ----
// Engineering values and value names (format_version 2), as homingd exports them.
std::string settings_file_text(const RawMap& values, const std::string& source, std::int64_t now_ms);
// A value as the file spells it ("1500.0", "\"negative\"", "true"), for messages.
std::string file_value_text(const registers::Register& reg, std::int64_t raw);
std::expected<void, std::string> write_file_atomically(const std::string& path, const std::string& text);

struct SettingsFileValues {
  RawMap values;                                // name -> raw
  std::map<std::string, std::uint32_t> lines;  // name -> line in the file
};
// The settings of a file (engineering values, or raw ones of a format_version 1
// file), each a setting of the module in its range. Every value that is not
// is named with file:line, the value and the rule, all in one error.
std::expected<SettingsFileValues, std::string> read_settings_file(const std::string& path);

}  // namespace homingctl
