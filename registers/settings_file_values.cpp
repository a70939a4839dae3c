#include "registers/settings_file_values.hpp"

#include <fmt/format.h>

#include <cstdlib>

#include "registers/defaults.hpp"
#include "registers/lookup.hpp"
#include "registers/value_text.hpp"

namespace registers {
namespace {

// Raw × scale as a decimal number, exactly (no binary floating point on the
// way): 2250 µm -> "2.25", 1500 mm/min -> "1500.0".
std::string decimal_text(const Register& reg, std::int64_t raw) {
  if (reg.scale() == 1.0) return fmt::format("{}.0", raw);
  const std::uint64_t magnitude = raw < 0 ? 0 - static_cast<std::uint64_t>(raw) : static_cast<std::uint64_t>(raw);
  std::string fraction = fmt::format("{:03}", magnitude % 1000);  // scale 0.001
  while (fraction.size() > 1 && fraction.back() == '0') fraction.pop_back();
  return fmt::format("{}{}.{}", raw < 0 ? "-" : "", magnitude / 1000, fraction);
}

const Register* setting_named(const std::string& name) {
  const Register* reg = find_register(name);
  return reg && reg->persisted ? reg : nullptr;
}

}  // namespace

std::string file_value_text(const std::string& name, std::int64_t raw,
                            const std::map<std::string, std::int64_t>& all) {
  const Register* reg = setting_named(name);
  if (!reg) return fmt::format("{}", raw);
  if (reg->type == Type::enumeration || reg->type == Type::bitmask) {
    const std::string text = value_text(*reg, raw);
    if (reg->type == Type::bitmask || !value_name(*reg, raw).empty()) return fmt::format("\"{}\"", text);
    return fmt::format("{}", raw);  // a number without a name (an old database)
  }
  if (is_flag(*reg)) return raw ? "true" : "false";
  const auto unit = reg->unit_text(kinds_of(settings_from_raw(all).settings));
  if (unit.empty()) return fmt::format("{}", raw);
  return fmt::format("{}  # {}", decimal_text(*reg, raw), unit);
}

std::expected<std::int64_t, std::string> raw_of_file_value(const std::string& name, const FileValue& value) {
  const Register* reg = setting_named(name);
  if (!reg) return std::unexpected(fmt::format("{} is not a setting of this module", name));
  switch (value.index()) {
    case 0: return parse_value(*reg, fmt::format("{}", std::get<std::int64_t>(value)));
    case 1: {
      const std::string text = fmt::format("{}", std::get<double>(value));
      if (reg->type == Type::enumeration || reg->type == Type::bitmask || is_flag(*reg))
        return std::unexpected(fmt::format("{} = {}: a decimal number, but the setting takes {}", name, text,
                                           accepted_text(*reg)));
      return parse_value(*reg, text);
    }
    case 2: {
      const bool on = std::get<bool>(value);
      if (!is_flag(*reg))
        return std::unexpected(fmt::format("{} = {}: true/false is for flags; the setting takes {}", name,
                                           on ? "true" : "false", accepted_text(*reg)));
      return on ? 1 : 0;
    }
    default: return parse_value(*reg, std::get<std::string>(value));
  }
}

}  // namespace registers
