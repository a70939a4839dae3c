#include "values.hpp"

#include <fmt/format.h>

#include <cctype>

#include "registers/codec.hpp"

namespace homingctl {

using registers::Register;
using registers::Type;

namespace {

std::string trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return std::string(s);
}

}  // namespace

nlohmann::json value_json(const Register& reg, std::int64_t raw, const registers::AxisKinds& kinds) {
  nlohmann::json j;
  j["raw"] = raw;
  j["value"] = registers::to_engineering(reg, raw);
  j["unit"] = std::string(reg.unit_text(kinds));
  if (reg.type == Type::enumeration || reg.type == Type::bitmask) j["text"] = value_text(reg, raw);
  return j;
}

std::expected<std::pair<std::string, std::string>, std::string> split_assignment(std::string_view arg) {
  const auto eq = arg.find('=');
  if (eq == std::string_view::npos || eq == 0)
    return std::unexpected(fmt::format("'{}': expected NAME=VALUE, e.g. axis.x.seek_feedrate=1200", arg));
  return std::pair{trim(arg.substr(0, eq)), trim(arg.substr(eq + 1))};
}

}  // namespace homingctl
