#pragma once
// How a setting is spelled in a settings file of engineering values
// (persistence/settings_file.hpp, format_version 2): the register layer's half
// of persistence::SettingsFileCodec. Units and value names come from the row
// (its quantity, scale and value list), as homingctl get/set spell them.
//   axis.x.seek_feedrate = 1500.0  # mm/min
//   axis.x.pull_off = 2.25  # mm
//   axis.x.direction = "negative"
//   axis.x.sensor_nc = false
//   sequence.step1 = "z"
//   global.history_max_rows = 10000
#include <cstdint>
#include <expected>
#include <map>
#include <string>
#include <variant>

namespace registers {

// persistence::SettingsFileValue: an integer, a decimal number, true/false or a text.
using FileValue = std::variant<std::int64_t, double, bool, std::string>;

// The TOML value of a setting's raw value, with its unit as a comment when it
// has one. Exact: reading it back gives the same raw value. `all` holds every
// setting of the file (name -> raw): the unit of a per-axis value is that of
// the kind the axis moves with there (axis.<a>.kind, a slave its master's);
// a setting missing from `all` has its default.
std::string file_value_text(const std::string& name, std::int64_t raw,
                            const std::map<std::string, std::int64_t>& all);

// A file value as the raw value: numbers in the register's unit, value names
// (or their numbers) for lists, true/false or 0/1 for flags, and texts as
// homingctl set takes them ("2.5 mm"). Range-checked; the error names the
// setting, the value and the rule.
std::expected<std::int64_t, std::string> raw_of_file_value(const std::string& name, const FileValue& value);

}  // namespace registers
