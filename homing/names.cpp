// Names of enum values, from the tables beside each enum (enum_info.hpp):
// used in logs, exports and homingctl.
#include "alarms.hpp"
#include "phases.hpp"
#include "settings.hpp"
#include "status.hpp"

namespace homing {

std::string_view field_name(AxisField f) { return name_of(f); }
std::string_view mode_name(HomingMode m) { return name_of(m); }
std::string_view phase_name(Phase p) { return name_of(p); }
std::string_view alarm_name(AlarmCode c) { return name_of(c); }
std::string_view state_name(MachineState s) { return name_of(s); }
std::string_view command_result_name(CommandResult r) { return name_of(r); }

std::string_view alarm_what_to_check(AlarmCode c) {
  const auto* e = entry_of(c);
  return e ? e->what_to_check : "?";
}

std::string_view alarm_value_unit_name(AlarmCode c) {
  const auto* e = entry_of(c);
  switch (e ? e->value_unit : AlarmValueUnit::axis) {
    case AlarmValueUnit::axis: return "axis";
    case AlarmValueUnit::seconds: return "s";
    case AlarmValueUnit::setting: return "setting";
  }
  return "axis";
}

std::string_view interlock_name(int bit) {
  return bit >= 0 && bit < interlock::kCount ? interlock::kInfo[bit].text : "?";
}

}  // namespace homing
