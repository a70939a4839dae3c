#pragma once
// Engineering values of registers as people type and read them.
#include <cstdint>
#include <expected>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "registers/table.hpp"

namespace homingctl {

// "12.5", "12.5mm", "switch_reapproach", "2", "on", "x+y" (bitmask) -> raw.
// Range-checked against the table; the error says what is accepted.
std::expected<std::int64_t, std::string> parse_value(const registers::Register& reg, std::string_view text);

// "12.5 mm", "switch_reapproach", "x+y", "1" (flags), for tables.
std::string value_text(const registers::Register& reg, std::int64_t raw);

// {"raw":..,"value":..,"unit":..,"name":..}
nlohmann::json value_json(const registers::Register& reg, std::int64_t raw);

// "1 mm .. 60000 mm", or the enum names.
std::string accepted_text(const registers::Register& reg);

// Splits "NAME=VALUE".
std::expected<std::pair<std::string, std::string>, std::string> split_assignment(std::string_view arg);

}  // namespace homingctl
