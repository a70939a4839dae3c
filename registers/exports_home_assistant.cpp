// Home Assistant `modbus:` integration YAML: registers as sensors, discrete
// inputs as binary_sensors, coils as switches. Host and port are the
// development defaults; the README says what to change.
//
// Scan intervals: Home Assistant warns below 5 s, and polls every entity on
// its own timer, so live values poll at 5 s and settings (which change only
// when someone writes them) at 60 s. Every switch verifies by reading its coil
// back: a command coil reads 0 once taken, so its switch falls back to "off"
// right after the press, which is how a momentary button behaves there.
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

constexpr int kLiveScan_s = 5;       // status, positions, alarms, held coils
constexpr int kSettingScan_s = 60;   // holding registers and command read-back

std::string entity(const Register& r) {
  return fmt::format("      - name: \"homing {}\"\n        unique_id: homing_{}_{}\n        slave: {}\n        address: {}\n",
                     r.name(), unit_name(r.unit), exports_detail::flat_name(r),
                     exports_detail::default_unit_id(r.unit), r.address);
}

}  // namespace

std::string export_home_assistant(const MapUnits& units) {
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
        if (const auto unit = r.unit_text(units.kinds); !unit.empty())
          sensors += fmt::format("        unit_of_measurement: \"{}\"\n", unit);
        sensors += fmt::format("        scan_interval: {}\n",
                               r.table == Table::holding_register ? kSettingScan_s : kLiveScan_s);
        break;
      }
      case Table::discrete_input:
        binary_sensors +=
            entity(r) + fmt::format("        input_type: discrete_input\n        scan_interval: {}\n", kLiveScan_s);
        break;
      case Table::coil:
        // Held coils read back their state; command coils read back 0, so the
        // verify read turns their switch off again (a momentary button).
        switches += entity(r) + fmt::format(
                                    "        write_type: coil\n        command_on: 1\n        command_off: 0\n"
                                    "        scan_interval: {}\n"
                                    "        verify:\n          input_type: coil\n          address: {}\n"
                                    "          state_on: 1\n          state_off: 0\n",
                                    r.access == Access::rw ? kLiveScan_s : kSettingScan_s, r.address);
        break;
    }
  }
  return fmt::format(
      "# {}\n"
      "# Paste under your configuration.yaml (or !include it). 32-bit values are high word first;\n"
      "# if the module runs with --word-order low-first add `swap: word` to the int32/uint32 sensors.\n"
      "# Settings are sensors here; change one with the modbus.write_register action, raw value =\n"
      "# engineering value / scale, a negative one as its two's complement, both words of a 32-bit\n"
      "# value in one call: axis.x.home_position = -12.5 mm -> raw -12500 -> value: [65535, 53036].\n"
      "modbus:\n  - name: homing_module\n    type: tcp\n    host: 127.0.0.1\n    port: 1502\n"
      "    sensors:\n{}    binary_sensors:\n{}    switches:\n{}",
      exports_detail::generated_note(units), sensors, binary_sensors, switches);
}

}  // namespace registers
