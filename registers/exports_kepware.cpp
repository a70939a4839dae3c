// KEPServerEX / Kepware Modbus Ethernet driver: CSV tag import, one file per
// device (unit id). Addresses are the driver's 6-digit 1-based references
// (400101 = holding register address 100). Tag names are the dotted register
// names: Kepware's CSV import turns each dot into a tag group (axis.x.mode ->
// group axis, group x, tag mode).
//
// The file is plain ASCII: KEPServerEX reads a CSV without a byte-order mark
// in the Windows code page, so UTF-8 "µm" or "mm/s²" would import as
// mojibake. Units and descriptions are spelled in ASCII instead.
#include <fmt/format.h>

#include "registers/codec.hpp"
#include "registers/exports.hpp"

namespace registers {
namespace {

// Kepware truncates longer descriptions; an enum list that does not fit points
// to the enum value lists beside the maps instead.
constexpr std::size_t kMaxDescription = 255;

std::string_view kepware_type(Type t) {
  switch (t) {
    case Type::boolean: return "Boolean";
    case Type::i16: return "Short";
    case Type::u32: return "DWord";
    case Type::i32: return "Long";
    default: return "Word";
  }
}

std::string values_text(const Register& r) {
  std::string out = r.type == Type::bitmask ? "bits: " : "";
  const std::size_t first = out.size();
  for (const EnumValue& v : r.values)
    out += fmt::format("{}{}={}", out.size() == first ? "" : ", ", v.value, v.name);
  return out;
}

std::string description(const Register& r, const MapUnits& units) {
  std::string d = exports_detail::description(r, units);
  if (!r.values.empty()) {
    const std::string with_values = fmt::format("{} ({})", d, values_text(r));
    d = with_values.size() <= kMaxDescription ? with_values : d + " (values: see registers.md)";
  }
  return exports_detail::ascii_text(d);
}

}  // namespace

std::string export_kepware(Unit unit, const MapUnits& units) {
  using exports_detail::csv_field;
  std::string out =
      "Tag Name,Address,Data Type,Respect Data Type,Client Access,Scan Rate,Scaling,Raw Low,Raw High,"
      "Scaled Low,Scaled High,Scaled Data Type,Clamp Low,Clamp High,Eng Units,Description,Negate Value\n";
  for (const Register& r : registers_of(unit)) {
    const bool scaled = r.scale() != 1.0;
    const std::string scaling =
        scaled ? fmt::format("Linear,0,{},0,1,Double,0,0", static_cast<long long>(1.0 / r.scale() + 0.5))
               : std::string(",,,,,,,");
    out += fmt::format("{},{},{},1,{},100,{},{},{},0\n", r.name(), modbus_reference(r.table, r.address),
                       kepware_type(r.type), r.writable() ? "R/W" : "RO", scaling,
                       csv_field(exports_detail::ascii_text(r.unit_text(units.kinds))),
                       csv_field(description(r, units)));
  }
  return out;
}

}  // namespace registers
