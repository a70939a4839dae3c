#pragma once
// Engineering values of registers as people type and read them.
#include <cstdint>
#include <expected>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "registers/table.hpp"
#include "registers/value_text.hpp"

namespace homingctl {

// parse_value, value_text and accepted_text: the register layer's, shared
// with the settings file (registers/value_text.hpp).
using registers::accepted_text;
using registers::parse_value;
using registers::value_text;

// {"raw":..,"value":..,"unit":..,"name":..}
nlohmann::json value_json(const registers::Register& reg, std::int64_t raw,
                          const registers::AxisKinds& kinds = registers::default_kinds());

// Splits "NAME=VALUE".
std::expected<std::pair<std::string, std::string>, std::string> split_assignment(std::string_view arg);

}  // namespace homingctl
