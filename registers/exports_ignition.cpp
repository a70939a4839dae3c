// Ignition (Inductive Automation) tag import JSON: OPC tags on the built-in
// Modbus TCP driver, one folder per dotted name part. Item paths use the
// driver's 1-based designators (HRUS101 = holding register address 100) with
// the unit id as prefix, so one device serves both units.
#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "registers/exports.hpp"

namespace registers {
namespace {

using nlohmann::ordered_json;

std::string_view designator(const Register& r) {
  const bool hr = r.table == Table::holding_register;
  switch (r.table) {
    case Table::coil: return "C";
    case Table::discrete_input: return "DI";
    default: break;
  }
  switch (r.type) {
    case Type::i16: return hr ? "HR" : "IR";
    case Type::u32: return hr ? "HRUI" : "IRUI";
    case Type::i32: return hr ? "HRI" : "IRI";
    default: return hr ? "HRUS" : "IRUS";
  }
}

std::string_view ignition_type(const Register& r) {
  if (r.scale() != 1.0) return "Float8";
  switch (r.type) {
    case Type::boolean: return "Boolean";
    case Type::i16: return "Int2";
    case Type::u32: return "Int8";  // Int4 is signed 32-bit
    default: return "Int4";         // u16 and i32 both fit
  }
}

ordered_json& folder(ordered_json& parent, const std::string& name) {
  for (auto& t : parent["tags"])
    if (t["name"] == name) return t;
  parent["tags"].push_back({{"name", name}, {"tagType", "Folder"}, {"tags", ordered_json::array()}});
  return parent["tags"].back();
}

}  // namespace

std::string export_ignition(const MapUnits& units) {
  ordered_json root{{"name", "HomingModule"}, {"tagType", "Folder"}, {"tags", ordered_json::array()}};
  for (Unit unit : {Unit::module, Unit::simulator}) {
    ordered_json& top = folder(root, unit == Unit::module ? "module" : "simulator");
    for (const Register& r : registers_of(unit)) {
      std::string name = r.name();
      ordered_json* parent = &top;
      for (std::size_t dot; (dot = name.find('.')) != std::string::npos; name.erase(0, dot + 1))
        parent = &folder(*parent, name.substr(0, dot));
      ordered_json tag{{"name", name},
                       {"tagType", "AtomicTag"},
                       {"valueSource", "opc"},
                       {"opcServer", "Ignition OPC UA Server"},
                       {"opcItemPath", fmt::format("ns=1;s=[HomingModule]{}.{}{}", exports_detail::default_unit_id(unit),
                                                   designator(r), std::uint32_t{r.address} + 1)},
                       {"dataType", ignition_type(r)},
                       {"documentation", exports_detail::description(r, units)},
                       {"readOnly", !r.writable()}};
      if (const auto unit = r.unit_text(units.kinds); !unit.empty()) tag["engUnit"] = unit;
      if (r.scale() != 1.0) {
        tag["scaleMode"] = "Linear";
        tag["rawLow"] = 0;
        tag["rawHigh"] = 1000;
        tag["scaledLow"] = 0;
        tag["scaledHigh"] = 1000 * r.scale();
      }
      parent->at("tags").push_back(tag);
    }
  }
  return root.dump(2) + "\n";
}

}  // namespace registers
