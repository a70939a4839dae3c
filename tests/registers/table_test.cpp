// The table itself: every name the spec promises, unique names, one stride per
// table, enum names in step with the engine's. Unique addresses and ranges that
// fit their types are static_asserts in registers/table.cpp, not tests.
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <map>
#include <set>
#include <string>
#include <vector>

#include "homing/alarms.hpp"
#include "homing/phases.hpp"
#include "homing/settings.hpp"
#include "homing/status.hpp"
#include "registers/codec.hpp"
#include "registers/lookup.hpp"
#include "registers/table.hpp"

using namespace registers;

namespace {

std::vector<std::string> per_axis(std::initializer_list<const char*> patterns) {
  std::vector<std::string> out;
  for (const char* p : patterns)
    for (auto letter : homing::kAxisLetters) {
      std::string n = p;
      n.replace(n.find("<a>"), 3, letter);
      out.push_back(n);
    }
  return out;
}

struct Expected {
  std::string name;
  Unit unit;
  Table table;
};

std::vector<Expected> spec_names() {
  std::vector<Expected> out;
  auto add = [&](Unit u, Table t, const std::vector<std::string>& names) {
    for (const auto& n : names) out.push_back({n, u, t});
  };
  const auto M = Unit::module;
  const auto S = Unit::simulator;
  add(M, Table::holding_register,
      per_axis({"axis.<a>.mode", "axis.<a>.direction", "axis.<a>.seek_feedrate", "axis.<a>.latch_feedrate",
                "axis.<a>.acceleration", "axis.<a>.max_seek_travel", "axis.<a>.max_stop_distance",
                "axis.<a>.max_backoff", "axis.<a>.pull_off", "axis.<a>.home_position", "axis.<a>.final_position",
                "axis.<a>.final_move_enable", "axis.<a>.sensor_nc", "axis.<a>.debounce_ms",
                "axis.<a>.pre_move_mode", "axis.<a>.pre_move_distance", "axis.<a>.push_distance",
                "axis.<a>.slave_of", "axis.<a>.slave_mode", "axis.<a>.max_misalignment",
                "axis.<a>.switch_compensation", "axis.<a>.soft_limit_min", "axis.<a>.soft_limit_max",
                "axis.<a>.soft_limits_enable", "axis.<a>.shared_limit", "axis.<a>.jog_feedrate",
                "axis.<a>.index_pitch", "axis.<a>.target"}));
  add(M, Table::holding_register,
      {"sequence.step1", "sequence.step2", "sequence.step3", "sequence.step4", "sequence.step5", "sequence.step6",
       "global.allowed_without_homing", "global.alarm_clears_homed", "global.watchdog_ms",
       "global.permit_required", "host.heartbeat"});
  add(M, Table::coil, {"cmd.home_all", "cmd.abort", "cmd.reset_alarm", "host.homing_permit"});
  add(M, Table::coil, per_axis({"cmd.home.<a>", "cmd.jog_plus.<a>", "cmd.jog_minus.<a>", "cmd.move.<a>"}));
  add(M, Table::input_register,
      {"status.state", "status.sequence_step", "status.homing_cycles", "status.heartbeat", "status.map_version",
       "status.last_command_result", "status.interlocks", "status.global_alarm"});
  add(M, Table::input_register,
      per_axis({"axis.<a>.phase", "axis.<a>.alarm", "axis.<a>.position", "axis.<a>.home_correction",
                "axis.<a>.stop_distance", "axis.<a>.alarm_phase", "axis.<a>.trigger_position",
                "axis.<a>.velocity", "axis.<a>.phase_distance", "axis.<a>.correction_mean",
                "axis.<a>.correction_spread"}));
  add(M, Table::discrete_input, per_axis({"axis.<a>.homed", "axis.<a>.sensor", "axis.<a>.busy"}));
  add(M, Table::discrete_input, {"status.alarm", "status.homing", "status.estop"});
  add(S, Table::holding_register,
      per_axis({"sim.<a>.actual_position", "sim.<a>.sensor_min", "sim.<a>.sensor_max", "sim.<a>.hysteresis",
                "sim.<a>.noise", "sim.<a>.bounce_ms", "sim.<a>.sensor_nc", "sim.<a>.hard_stop_min",
                "sim.<a>.hard_stop_max", "sim.<a>.index_pitch", "sim.<a>.index_offset",
                "sim.<a>.absolute_offset", "sim.<a>.fault", "sim.<a>.lose_steps"}));
  add(S, Table::holding_register, {"sim.seed"});
  add(S, Table::coil, {"sim.estop", "sim.start_button"});
  add(S, Table::discrete_input, per_axis({"sim.<a>.sensor", "sim.<a>.at_hard_stop"}));
  return out;
}

}  // namespace

TEST_CASE("every name the spec promises is in the table, in the right unit and table") {
  for (const Expected& e : spec_names()) {
    INFO(e.name);
    const Register* r = find_register(e.name);
    REQUIRE(r != nullptr);
    CHECK(r->unit == e.unit);
    CHECK(r->table == e.table);
  }
}

TEST_CASE("32-bit values named i32/u32 by the spec take two words") {
  for (const char* n : {"status.homing_cycles", "axis.x.position", "axis.c.home_correction",
                        "axis.y.trigger_position", "sim.z.actual_position", "sim.x.sensor_min", "sim.b.lose_steps",
                        "sim.a.hard_stop_max"}) {
    INFO(n);
    REQUIRE(find_register(n) != nullptr);
    CHECK(find_register(n)->words() == 2);
  }
}

TEST_CASE("names are unique across the whole table") {
  std::set<std::string> names;
  for (const Register& r : all_registers()) CHECK(names.insert(r.name()).second);
}

TEST_CASE("every per-axis register sits at base + stride * axis + the same offset on all six axes") {
  std::map<std::pair<Unit, std::string>, std::vector<const Register*>> by_pattern;
  for (const Register& r : all_registers())
    if (r.per_axis()) by_pattern[{r.unit, std::string(r.pattern)}].push_back(&r);
  REQUIRE(!by_pattern.empty());
  for (const auto& [key, rows] : by_pattern) {
    INFO(key.second);
    REQUIRE(rows.size() == homing::kAxisCount);
    for (const Register* r : rows) {
      const AxisBlock b = axis_block(r->table);
      CHECK(r->address == b.base + b.stride * r->axis + rows.front()->offset);
      CHECK(r->offset == rows.front()->offset);
      CHECK(r->offset + r->words() <= b.stride);
    }
  }
}

TEST_CASE("lookup by address finds both words of a 32-bit register and nothing in a gap") {
  const Register* pos = find_register("axis.y.position");
  REQUIRE(pos);
  CHECK(find_register(Unit::module, Table::input_register, pos->address) == pos);
  CHECK(find_register(Unit::module, Table::input_register, pos->address + 1) == pos);
  CHECK(find_register(Unit::module, Table::holding_register, 99) == nullptr);
  CHECK(find_register(Unit::simulator, Table::input_register, 0) == nullptr);
}

TEST_CASE("registers overlapping a range include a 32-bit register cut by either end of it") {
  const Register* pos = find_register("axis.y.position");
  REQUIRE(pos);
  const auto from_second_word = registers_overlapping(Unit::module, Table::input_register, pos->address + 1, 1);
  REQUIRE(from_second_word.size() == 1);
  CHECK(&from_second_word.front() == pos);
  const auto to_first_word = registers_overlapping(Unit::module, Table::input_register, pos->address - 1, 2);
  REQUIRE_FALSE(to_first_word.empty());
  CHECK(&to_first_word.back() == pos);
  const auto before = registers_overlapping(Unit::module, Table::input_register, pos->address - 1, 1);
  CHECK((before.empty() || &before.back() != pos));
  CHECK(registers_overlapping(Unit::module, Table::holding_register, 90, 4).empty());
  CHECK(registers_overlapping(Unit::simulator, Table::input_register, 0, 1).empty());
  // The whole address space of a table holds every register of it, and only those.
  std::size_t coils = 0;
  for (const Register& r : all_registers()) coils += r.unit == Unit::module && r.table == Table::coil;
  CHECK(registers_overlapping(Unit::module, Table::coil, 0, 65536).size() == coils);
}

TEST_CASE("enum value names in the table match the engine's names") {
  auto values_of = [](const char* name) { return find_register(name)->values; };
  for (const auto& v : values_of("axis.x.mode"))
    CHECK(v.name == homing::mode_name(static_cast<homing::HomingMode>(v.value)));
  CHECK(values_of("axis.x.mode").size() == homing::kHomingModeCount);
  for (const auto& v : values_of("axis.x.phase"))
    CHECK(v.name == homing::phase_name(static_cast<homing::Phase>(v.value)));
  for (const auto& v : values_of("axis.x.alarm"))
    CHECK(v.name == homing::alarm_name(static_cast<homing::AlarmCode>(v.value)));
  CHECK(values_of("axis.x.alarm").size() == homing::kAlarmCodeCount);
  for (const auto& v : values_of("status.state"))
    CHECK(v.name == homing::state_name(static_cast<homing::MachineState>(v.value)));
  for (const auto& v : values_of("status.last_command_result"))
    CHECK(v.name == homing::command_result_name(static_cast<homing::CommandResult>(v.value)));
  CHECK(values_of("status.last_command_result").size() == homing::kCommandResultCount);
  for (const auto& v : values_of("status.interlocks"))
    CHECK(v.meaning == homing::interlock_name(static_cast<int>(v.value)));
  CHECK(values_of("status.interlocks").size() == static_cast<std::size_t>(homing::interlock::kCount));
}

TEST_CASE("per-axis setting names are the engine's field names") {
  for (const Register& r : registers_of(Unit::module)) {
    if (!r.persisted || !r.per_axis()) continue;
    const std::string suffix = r.name().substr(std::string("axis.x.").size());
    bool found = false;
    for (const auto& f : homing::kAxisFieldInfo)
      found |= f.value != homing::AxisField::none && homing::field_name(f.value) == suffix;
    INFO(r.name());
    CHECK(found);
  }
}

TEST_CASE("map version is published from the table") {
  const Register* r = find_register("status.map_version");
  REQUIRE(r);
  CHECK(r->default_raw == kMapVersion);
  homing::Settings s;
  HostRegisters h;
  homing::Status st;
  StatusExtras ex;
  CHECK(read_raw(*r, ModuleView{s, h, st, ex}) == kMapVersion);
}

TEST_CASE("rotary axes show degrees, linear axes millimetres") {
  CHECK(find_register("axis.x.max_seek_travel")->unit_text() == "mm");
  CHECK(find_register("axis.a.max_seek_travel")->unit_text() == "deg");
  CHECK(find_register("axis.c.seek_feedrate")->unit_text() == "deg/min");
  CHECK(find_register("axis.z.acceleration")->unit_text() == "mm/s²");
  CHECK(find_register("axis.x.pull_off")->scale() == 0.001);
  CHECK(find_register("axis.x.seek_feedrate")->scale() == 1.0);
}
