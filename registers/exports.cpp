// The list of generated files and the helpers every exporter shares.
#include "registers/exports.hpp"

#include <fmt/format.h>

#include "registers/codec.hpp"

namespace registers {

std::vector<GeneratedFile> generate_hmi_maps() {
  return {
      {"registers.csv", export_csv(Unit::module)},
      {"sim_registers.csv", export_csv(Unit::simulator)},
      {"registers.md", export_markdown()},
      {"registers.json", export_json()},
      {"kepware_module.csv", export_kepware(Unit::module)},
      {"kepware_simulator.csv", export_kepware(Unit::simulator)},
      {"ignition_tags.json", export_ignition()},
      {"home_assistant_modbus.yaml", export_home_assistant()},
      {"alarms.csv", export_alarms_csv()},
      {"enums.csv", export_enums_csv()},
  };
}

namespace exports_detail {

std::string csv_field(std::string_view s) {
  if (s.find_first_of(",\"\n") == std::string_view::npos) return std::string(s);
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string scale_text(const Register& reg) { return fmt::format("{}", reg.scale()); }

std::string engineering_text(const Register& reg, std::int64_t raw) {
  return fmt::format("{}", to_engineering(reg, raw));
}

std::string flat_name(const Register& reg) {
  std::string n = reg.name();
  for (char& c : n)
    if (c == '.') c = '_';
  return n;
}

std::string description(const Register& reg) {
  std::string d(reg.description);
  if (const auto at = d.find("<a>"); at != std::string::npos && reg.axis >= 0)
    d.replace(at, 3, homing::kAxisLetters[static_cast<std::size_t>(reg.axis)]);
  return d;
}

std::uint8_t default_unit_id(Unit unit) {
  return unit == Unit::module ? kDefaultModuleUnitId : kDefaultSimUnitId;
}

}  // namespace exports_detail
}  // namespace registers
