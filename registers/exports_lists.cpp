// alarms.csv and enums.csv: lists for HMI alarm and text-list imports. The
// alarm list is the engine's own alarm table (homing/alarms.hpp); the enum
// lists are the table's value lists, which come from the engine's enum tables.
#include <fmt/format.h>

#include "homing/alarms.hpp"
#include "registers/errors.hpp"
#include "registers/exports.hpp"

namespace registers {

std::string export_alarms_csv() {
  using exports_detail::csv_field;
  // alarm_value_unit: what the axis's alarm_value (declared in the axis's
  // unit) is in for this alarm, so an HMI labels the figure right.
  std::string out = "code,name,text,what_to_check,alarm_value_unit\n";
  for (const homing::AlarmInfo& a : homing::kAlarmInfo) {
    if (a.value == homing::AlarmCode::none) continue;  // "no alarm" is not an alarm to import
    out += fmt::format("{},{},{},{},{}\n", static_cast<int>(a.value), csv_field(a.name), csv_field(a.text),
                       csv_field(a.what_to_check), homing::alarm_value_unit_name(a.value));
  }
  return out;
}

std::string export_refusals_csv() {
  using exports_detail::csv_field;
  // The reasons' texts say what to do already; each rule has its fix beside it.
  std::string out = "code,name,exception,text,fix\n";
  for (const RefusalReasonInfo& r : kRefusalReasonInfo) {
    if (r.value == RefusalReason::none || r.value == RefusalReason::rule) continue;  // a rule has its own codes
    out += fmt::format("{},{},{:02X},{},\n", static_cast<int>(r.value), csv_field(r.name), static_cast<int>(r.exception),
                       csv_field(r.text));
  }
  const auto rule_exception = static_cast<int>(kRefusalReasonInfo[static_cast<std::size_t>(RefusalReason::rule)].exception);
  for (const auto& r : homing::kCheckRuleInfo) {
    if (r.value == homing::CheckRule::none) continue;
    out += fmt::format("{},{},{:02X},{},{}\n", kRuleReasonBase + static_cast<int>(r.value), csv_field(r.name),
                       rule_exception, csv_field("combination refused: " + std::string(r.text)),
                       csv_field(homing::rule_fix(r.value)));
  }
  return out;
}

std::string export_enums_csv() {
  using exports_detail::csv_field;
  std::string out = "enum,value,name,text\n";
  for (const ValueList& list : value_lists())
    for (const EnumValue& v : list.values)
      out += fmt::format("{},{},{},{}\n", csv_field(list.name), v.value, csv_field(v.name), csv_field(v.meaning));
  return out;
}

}  // namespace registers
