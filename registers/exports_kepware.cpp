// KEPServerEX / Kepware Modbus Ethernet driver: CSV tag import, one file per
// device (unit id). Addresses are the driver's 6-digit 1-based references
// (400101 = holding register address 100). Tag names cannot contain dots.
#include <fmt/format.h>

#include "registers/codec.hpp"
#include "registers/exports.hpp"

namespace registers {
namespace {

std::string_view kepware_type(Type t) {
  switch (t) {
    case Type::boolean: return "Boolean";
    case Type::i16: return "Short";
    case Type::u32: return "DWord";
    case Type::i32: return "Long";
    default: return "Word";
  }
}

}  // namespace

std::string export_kepware(Unit unit) {
  using exports_detail::csv_field;
  std::string out =
      "Tag Name,Address,Data Type,Respect Data Type,Client Access,Scan Rate,Scaling,Raw Low,Raw High,"
      "Scaled Low,Scaled High,Scaled Data Type,Clamp Low,Clamp High,Eng Units,Description,Negate Value\n";
  for (const Register& r : registers_of(unit)) {
    const bool scaled = r.scale() != 1.0;
    const std::string scaling =
        scaled ? fmt::format("Linear,0,{},0,1,Double,0,0", static_cast<long long>(1.0 / r.scale() + 0.5))
               : std::string(",,,,,,,");
    out += fmt::format("{},{},{},1,{},100,{},{},{},0\n", exports_detail::flat_name(r),
                       modbus_reference(r.table, r.address), kepware_type(r.type),
                       r.writable() ? "R/W" : "RO", scaling, csv_field(r.unit_text()),
                       csv_field(exports_detail::description(r)));
  }
  return out;
}

}  // namespace registers
