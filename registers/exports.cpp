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
      {"refusals.csv", export_refusals_csv()},
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

std::string ascii_text(std::string_view utf8) {
  // The non-ASCII characters the table's units and descriptions use; a new
  // one fails the export test rather than slipping through.
  static constexpr std::pair<std::string_view, std::string_view> kSpelling[] = {
      {"\u00b5", "u"}, {"\u00b2", "^2"}, {"\u00b0", "deg"}, {"\u00b1", "+/-"}, {"\u00d7", "x"},
      {"\u2013", "-"}, {"\u2014", "-"}, {"\u2192", "->"}, {"\u2026", "..."}, {"\u2264", "<="},
      {"\u2265", ">="}, {"\u2260", "!="}, {"\u2018", "'"}, {"\u2019", "'"}, {"\u201c", "\""}, {"\u201d", "\""}};
  std::string out;
  for (std::size_t i = 0; i < utf8.size();) {
    bool replaced = false;
    for (const auto& [from, to] : kSpelling)
      if (utf8.substr(i, from.size()) == from) {
        out += to;
        i += from.size();
        replaced = true;
        break;
      }
    if (!replaced) out += utf8[i++];
  }
  return out;
}

std::uint8_t default_unit_id(Unit unit) {
  return unit == Unit::module ? kDefaultModuleUnitId : kDefaultSimUnitId;
}

}  // namespace exports_detail
}  // namespace registers
