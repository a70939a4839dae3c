// registers.json: the whole table for programs (HMI builders, homingctl, tests).
#include <nlohmann/json.hpp>

#include "registers/exports.hpp"

namespace registers {

std::string export_json(const MapUnits& units) {
  using nlohmann::ordered_json;
  ordered_json doc;
  doc["generated"] = exports_detail::generated_note(units);
  doc["map_version"] = kMapVersion;
  doc["word_order_default"] = "high_first";
  doc["address_base"] = 0;
  for (Unit unit : {Unit::module, Unit::simulator}) {
    ordered_json u;
    u["unit"] = unit_name(unit);
    u["default_unit_id"] = exports_detail::default_unit_id(unit);
    ordered_json blocks;
    for (Table t : {Table::coil, Table::discrete_input, Table::input_register, Table::holding_register})
      blocks[std::string(table_name(t))] = {{"base", axis_block(t).base}, {"stride", axis_block(t).stride}};
    u["axis_blocks"] = blocks;
    ordered_json regs = ordered_json::array();
    for (const Register& r : registers_of(unit)) {
      ordered_json j;
      j["name"] = r.name();
      j["table"] = table_name(r.table);
      j["address"] = r.address;
      j["words"] = r.words();
      j["type"] = type_name(r.type);
      j["access"] = access_name(r.access);
      j["unit"] = r.unit_text(units.kinds);
      j["scale"] = r.scale();
      j["min"] = r.min;
      j["max"] = r.max;
      j["default"] = r.default_raw;
      j["persisted"] = r.persisted;
      j["description"] = exports_detail::description(r, units);
      if (r.per_axis()) {
        j["axis"] = homing::kAxisLetters[static_cast<std::size_t>(r.axis)];
        j["offset"] = r.offset;
      }
      if (!r.values.empty()) {
        ordered_json vals = ordered_json::array();
        for (const EnumValue& v : r.values)
          vals.push_back({{r.type == Type::bitmask ? "bit" : "value", v.value}, {"name", v.name}, {"meaning", v.meaning}});
        j[r.type == Type::bitmask ? "bits" : "values"] = vals;
      }
      regs.push_back(j);
    }
    u["registers"] = regs;
    doc["units"].push_back(u);
  }
  return doc.dump(2) + "\n";
}

}  // namespace registers
