#include "registers/value_text.hpp"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>

#include "registers/codec.hpp"

namespace registers {

namespace {

std::string trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return std::string(s);
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string eng(const Register& reg, std::int64_t raw) { return fmt::format("{}", to_engineering(reg, raw)); }

}  // namespace

bool is_flag(const Register& reg) {
  return reg.type == Type::boolean ||
         (reg.min == 0 && reg.max == 1 && reg.values.empty() && reg.quantity == Quantity::none);
}

std::string accepted_text(const Register& reg, const AxisKinds& kinds) {
  if (!reg.values.empty() && reg.type == Type::enumeration) {
    std::string s;
    for (const auto& v : reg.values) s += fmt::format("{}{} ({})", s.empty() ? "" : ", ", v.name, v.value);
    return s;
  }
  if (reg.type == Type::bitmask) {
    std::string s;
    for (const auto& v : reg.values) s += fmt::format("{}{}", s.empty() ? "" : "+", v.name);
    return fmt::format("bit names joined by '+' ({}), 'none', or a number {}..{}", s, reg.min, reg.max);
  }
  if (is_flag(reg)) return "0/1 (off/on)";
  const auto u = reg.unit_text(kinds);
  return fmt::format("{}{}{} .. {}{}{}", eng(reg, reg.min), u.empty() ? "" : " ", u, eng(reg, reg.max),
                     u.empty() ? "" : " ", u);
}

std::expected<std::int64_t, std::string> parse_value(const Register& reg, std::string_view input,
                                                     const AxisKinds& kinds) {
  const std::string text = trim(input);
  const std::string name = reg.name();
  auto bad = [&](std::string_view why) {
    return std::unexpected(fmt::format("{} = '{}': {}; accepted: {}", name, text, why, accepted_text(reg, kinds)));
  };
  if (text.empty()) return bad("no value");
  const std::string l = lower(text);
  std::int64_t raw = 0;
  bool done = false;
  // Enum value names and bitmask bit names.
  if (!reg.values.empty() && reg.type == Type::enumeration) {
    for (const auto& v : reg.values)
      if (l == v.name) {
        raw = v.value;
        done = true;
      }
  } else if (reg.type == Type::bitmask && !std::isdigit(static_cast<unsigned char>(l[0]))) {
    if (l == "none" || l == "-") {
      done = true;
    } else {
      std::size_t at = 0;
      while (at <= l.size()) {
        const auto next = l.find_first_of("+,|", at);
        const std::string part = l.substr(at, next == std::string::npos ? std::string::npos : next - at);
        bool found = false;
        for (const auto& v : reg.values)
          if (part == v.name) {
            raw |= std::int64_t{1} << v.value;
            found = true;
          }
        if (!found) return bad(fmt::format("'{}' is not a bit name", part));
        if (next == std::string::npos) break;
        at = next + 1;
      }
      done = true;
    }
  }
  if (!done && is_flag(reg)) {
    if (l == "on" || l == "true" || l == "yes") raw = 1, done = true;
    if (l == "off" || l == "false" || l == "no") raw = 0, done = true;
  }
  if (!done) {
    // A number, optionally followed by the register's unit.
    std::string num = l;
    const std::string unit = lower(std::string(reg.unit_text(kinds)));
    if (!unit.empty() && num.size() > unit.size() && num.ends_with(unit)) num = trim(num.substr(0, num.size() - unit.size()));
    double v = 0;
    const auto* b = num.data();
    const auto* e = num.data() + num.size();
    auto [p, ec] = std::from_chars(b, e, v);
    if (ec != std::errc() || p != e || !std::isfinite(v))
      return bad(reg.values.empty() ? "not a number" : "not a number or value name");
    if (reg.scale() == 1.0 && v != std::floor(v)) return bad("must be a whole number");
    const double scaled = v / reg.scale();
    if (std::abs(scaled - std::round(scaled)) > 1e-6 * std::max(1.0, std::abs(scaled)))
      return bad(fmt::format("finer than the register's step of {} {}", reg.scale(), reg.unit_text(kinds)));
    if (scaled < static_cast<double>(reg.min) - 0.5 || scaled > static_cast<double>(reg.max) + 0.5)
      return bad("out of range");
    raw = std::llround(scaled);
  }
  if (raw < reg.min || raw > reg.max) return bad("out of range");
  return raw;
}

std::string value_text(const Register& reg, std::int64_t raw, const AxisKinds& kinds) {
  if (reg.type == Type::enumeration) {
    const auto n = value_name(reg, raw);
    return n.empty() ? fmt::format("{}", raw) : std::string(n);
  }
  if (reg.type == Type::bitmask) {
    std::string s;
    for (const auto& v : reg.values)
      if (raw & (std::int64_t{1} << v.value)) s += fmt::format("{}{}", s.empty() ? "" : "+", v.name);
    return s.empty() ? "none" : s;
  }
  const auto u = reg.unit_text(kinds);
  return u.empty() ? eng(reg, raw) : fmt::format("{} {}", eng(reg, raw), u);
}

}  // namespace registers
