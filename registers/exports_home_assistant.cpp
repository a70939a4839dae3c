// Home Assistant `modbus:` integration YAML: registers as sensors, discrete
// inputs as binary_sensors, coils as switches. Host and port are the
// development defaults; the README says what to change.
#include <fmt/format.h>

#include "registers/exports.hpp"

namespace registers {
namespace {

std::string_view ha_data_type(Type t) {
  switch (t) {
    case Type::i16: return "int16";
    case Type::u32: return "uint32";
    case Type::i32: return "int32";
    default: return "uint16";
  }
}

std::string entity(const Register& r) {
  return fmt::format("      - name: \"homing {}\"\n        unique_id: homing_{}_{}\n        slave: {}\n        address: {}\n",
                     r.name(), unit_name(r.unit), exports_detail::flat_name(r),
                     exports_detail::default_unit_id(r.unit), r.address);
}

}  // namespace

std::string export_home_assistant() {
  std::string sensors, binary_sensors, switches;
  for (const Register& r : all_registers()) {
    switch (r.table) {
      case Table::holding_register:
      case Table::input_register: {
        const int precision = r.scale() == 1.0 ? 0 : 3;
        sensors += entity(r) + fmt::format("        input_type: {}\n        data_type: {}\n        scale: {}\n"
                                           "        precision: {}\n",
                                           r.table == Table::holding_register ? "holding" : "input",
                                           ha_data_type(r.type), r.scale(), precision);
        if (!r.unit_text().empty()) sensors += fmt::format("        unit_of_measurement: \"{}\"\n", r.unit_text());
        sensors += "        scan_interval: 1\n";
        break;
      }
      case Table::discrete_input:
        binary_sensors += entity(r) + "        input_type: discrete_input\n        scan_interval: 1\n";
        break;
      case Table::coil:
        switches += entity(r) + "        write_type: coil\n";
        if (r.access == Access::rw)  // held coils read back their state; pulse commands read 0
          switches += fmt::format("        verify:\n          input_type: coil\n          address: {}\n", r.address);
        break;
    }
  }
  return fmt::format(
      "# {}\n"
      "# Paste under your configuration.yaml (or !include it). 32-bit values are high word first;\n"
      "# if the module runs with --word-order low-first add `swap: word` to the int32/uint32 sensors.\n"
      "modbus:\n  - name: homing_module\n    type: tcp\n    host: 127.0.0.1\n    port: 1502\n"
      "    sensors:\n{}    binary_sensors:\n{}    switches:\n{}",
      exports_detail::kGeneratedNote, sensors, binary_sensors, switches);
}

}  // namespace registers
