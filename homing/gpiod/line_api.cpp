#include "line_api.hpp"

#include <fmt/format.h>

namespace homing::gpiod {

std::string describe(const LineSpec& s) {
  std::string line;
  if (const auto* offset = std::get_if<unsigned>(&s.line)) line = fmt::format("line {}", *offset);
  else line = fmt::format("line \"{}\"", std::get<std::string>(s.line));
  return fmt::format("{} ({}{})", s.role, s.chip.empty() ? "" : s.chip + " ", line);
}

}  // namespace homing::gpiod
