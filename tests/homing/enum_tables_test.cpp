// The tables beside the engine's enums (enum_info.hpp): every value has a
// name and a text, every alarm says what to check, and the alarm sentence a
// technician reads ends with the table's words.
#include <catch2/catch.hpp>

#include <set>
#include <string>

#include "homing/alarms.hpp"
#include "homing/phases.hpp"
#include "homing/settings.hpp"
#include "homing/sim/config.hpp"
#include "homing/status.hpp"
#include "rig.hpp"

using namespace homing;

namespace {

template <class Table>
void check_named_and_explained(const Table& table, const char* what) {
  std::set<std::string_view> names;
  for (const auto& e : table) {
    INFO(what << " " << static_cast<int>(e.value) << " " << e.name);
    CHECK_FALSE(e.name.empty());
    CHECK_FALSE(e.text.empty());
    CHECK(names.insert(e.name).second);
    CHECK(name_of(e.value) == e.name);
    CHECK(text_of(e.value) == e.text);
  }
}

}  // namespace

TEST_CASE("every value of the engine's enums has a unique name and a text") {
  check_named_and_explained(kModeTable, "mode");
  check_named_and_explained(kDirectionInfo, "direction");
  check_named_and_explained(kPreMoveInfo, "pre-move");
  check_named_and_explained(kSlaveModeInfo, "slave mode");
  check_named_and_explained(kAllowedWithoutHomingInfo, "allowed without homing");
  check_named_and_explained(kPhaseInfo, "phase");
  check_named_and_explained(kAlarmInfo, "alarm");
  check_named_and_explained(kMachineStateInfo, "state");
  check_named_and_explained(kCommandResultInfo, "command result");
  check_named_and_explained(sim::kFaultInfo, "simulated fault");
  std::set<std::string_view> bits;
  for (const auto& b : interlock::kInfo) {
    CHECK(bits.insert(b.name).second);
    CHECK(interlock_name(b.bit) == b.text);
  }
}

TEST_CASE("a number outside an enum reads as a question mark, not as another value") {
  CHECK(name_of(static_cast<Phase>(200)) == "?");
  CHECK(alarm_name(static_cast<AlarmCode>(kAlarmCodeCount)) == "?");
  CHECK(alarm_what_to_check(static_cast<AlarmCode>(kAlarmCodeCount)) == "?");
  CHECK(describe_alarm(0, Alarm{static_cast<AlarmCode>(kAlarmCodeCount)}, Settings{}) == "?");
  CHECK(interlock_name(interlock::kCount) == "?");
}

TEST_CASE("every alarm says what to check, and its sentence ends with those words") {
  Settings s;
  s.axes[0] = rig::typical_axis();
  CHECK(alarm_what_to_check(AlarmCode::none).empty());
  for (std::uint8_t c = 1; c < kAlarmCodeCount; ++c) {
    const auto code = static_cast<AlarmCode>(c);
    const std::string check(alarm_what_to_check(code));
    const std::string text = describe_alarm(0, Alarm{code, Phase::seek}, s);
    INFO(text);
    CHECK(check.size() > 10);
    REQUIRE(text.size() > check.size() + 2);
    CHECK(text.substr(text.size() - check.size() - 2) == "; " + check);
  }
}
