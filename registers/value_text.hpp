#pragma once
// Engineering values of registers as people type and read them: homingctl's
// get/set and the settings file (settings_file_values.hpp) spell values the
// same way, with the unit of the register's quantity and the value names of
// its list (homing/enum_info.hpp).
#include <cstdint>
#include <expected>
#include <string>
#include <string_view>

#include "registers/table.hpp"

namespace registers {

// A flag: 0/1, read and written as off/on.
bool is_flag(const Register& reg);

// "12.5", "12.5mm", "switch_reapproach", "2", "on", "x+y" (bitmask) -> raw.
// Range-checked against the table; the error names the register, the value
// and what is accepted.
// `kinds`: the kind each axis moves with (kinds_of the settings), which names
// the unit of a per-axis value; without settings, a new module's.
std::expected<std::int64_t, std::string> parse_value(const Register& reg, std::string_view text,
                                                     const AxisKinds& kinds = default_kinds());

// "12.5 mm", "switch_reapproach", "x+y", "1" (flags), for tables.
std::string value_text(const Register& reg, std::int64_t raw, const AxisKinds& kinds = default_kinds());

// "1 mm .. 60000 mm", or the enum names.
std::string accepted_text(const Register& reg, const AxisKinds& kinds = default_kinds());

}  // namespace registers
