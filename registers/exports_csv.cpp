// registers.csv / sim_registers.csv: the machine-readable map. Columns and
// their order are part of the contract (spec/modbus.md). min, max and default
// are raw register values; engineering value = raw × scale.
#include <fmt/format.h>

#include "registers/exports.hpp"

namespace registers {

std::string export_csv(Unit unit, const MapUnits& units) {
  using exports_detail::csv_field;
  std::string out = "name,table,address,words,type,access,unit,scale,min,max,default,persisted,description\n";
  for (const Register& r : registers_of(unit)) {
    out += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{}\n", csv_field(r.name()), table_name(r.table),
                       r.address, r.words(), type_name(r.type), access_name(r.access),
                       csv_field(r.unit_text(units.kinds)), exports_detail::scale_text(r), r.min, r.max, r.default_raw,
                       r.persisted ? "yes" : "no", csv_field(exports_detail::description(r, units)));
  }
  return out;
}

}  // namespace registers
