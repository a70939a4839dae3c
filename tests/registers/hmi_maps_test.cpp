// The committed hmi_maps/ must be what the table generates today.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "homing/alarms.hpp"
#include "registers/errors.hpp"
#include "registers/exports.hpp"
#include "registers/lookup.hpp"
#include "registers/table.hpp"

namespace {

std::string first_difference(const std::string& have, const std::string& want) {
  std::istringstream a(have), b(want);
  std::string la, lb;
  for (int line = 1;; ++line) {
    const bool ga = static_cast<bool>(std::getline(a, la));
    const bool gb = static_cast<bool>(std::getline(b, lb));
    if (!ga && !gb) return "(line endings differ)";
    if (la != lb || ga != gb)
      return "line " + std::to_string(line) + ":\n  committed: " + (ga ? la : "<end of file>") +
             "\n  generated: " + (gb ? lb : "<end of file>");
  }
}

}  // namespace

TEST_CASE("hmi_maps in the repository are fresh") {
  for (const auto& file : registers::generate_hmi_maps()) {
    const std::string path = std::string(HMI_MAPS_DIR) + "/" + file.name;
    std::ifstream in(path, std::ios::binary);
    std::stringstream have;
    have << in.rdbuf();
    INFO("hmi_maps/" << file.name << " is stale; regenerate with: build/bin/gen_hmi_maps --out hmi_maps\n"
                     << (in ? first_difference(have.str(), file.content) : "file missing"));
    CHECK((in && have.str() == file.content));
  }
}

TEST_CASE("registers.csv has exactly the columns of the contract") {
  const auto files = registers::generate_hmi_maps();
  for (const char* name : {"registers.csv", "sim_registers.csv"}) {
    const auto it = std::find_if(files.begin(), files.end(), [&](const auto& f) { return f.name == name; });
    REQUIRE(it != files.end());
    CHECK(it->content.substr(0, it->content.find('\n')) ==
          "name,table,address,words,type,access,unit,scale,min,max,default,persisted,description");
  }
}

namespace {

std::string generated(const std::string& name) {
  for (const auto& f : registers::generate_hmi_maps())
    if (f.name == name) return f.content;
  FAIL("hmi_maps/" << name << " is not generated");
  return "";
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

}  // namespace

TEST_CASE("alarms.csv lists every alarm code of the engine with its name, text and what to check") {
  const auto lines = lines_of(generated("alarms.csv"));
  REQUIRE(lines.size() == homing::kAlarmCodeCount);  // the header, then codes 1..n-1
  CHECK(lines[0] == "code,name,text,what_to_check,alarm_value_unit");
  for (std::uint8_t c = 1; c < homing::kAlarmCodeCount; ++c) {
    const auto code = static_cast<homing::AlarmCode>(c);
    INFO(lines[c]);
    CHECK(lines[c].rfind(std::to_string(c) + "," + std::string(homing::alarm_name(code)) + ",", 0) == 0);
    CHECK(lines[c].find(homing::alarm_what_to_check(code)) != std::string::npos);
  }
}

TEST_CASE("alarms.csv says which alarms quote seconds in alarm_value, so an HMI does not label a wait in mm") {
  const auto lines = lines_of(generated("alarms.csv"));
  const auto unit_of = [&](homing::AlarmCode code) {
    const std::string& line = lines.at(static_cast<std::size_t>(code));
    return line.substr(line.rfind(',') + 1);
  };
  CHECK(unit_of(homing::AlarmCode::stall_timeout) == "s");
  CHECK(unit_of(homing::AlarmCode::drive_no_answer) == "s");
  CHECK(unit_of(homing::AlarmCode::drive_answered_at_once) == "s");
  CHECK(unit_of(homing::AlarmCode::settings_fault) == "setting");
  CHECK(unit_of(homing::AlarmCode::sensor_not_found) == "axis");
  CHECK(unit_of(homing::AlarmCode::misalignment) == "axis");
}

TEST_CASE("refusals.csv lists every code status.last_refusal_reason can take, with its exception") {
  const auto lines = lines_of(generated("refusals.csv"));
  REQUIRE(!lines.empty());
  CHECK(lines[0] == "code,name,exception,text,fix");
  const std::set<std::string> rows(lines.begin() + 1, lines.end());
  const auto listed = [&](std::int64_t code, std::string_view name, std::string_view exception) {
    return std::any_of(rows.begin(), rows.end(), [&](const std::string& row) {
      return row.rfind(std::to_string(code) + "," + std::string(name) + "," + std::string(exception) + ",", 0) == 0;
    });
  };
  std::size_t expected = 0;
  for (const auto& r : registers::kRefusalReasonInfo) {
    if (r.value == registers::RefusalReason::none || r.value == registers::RefusalReason::rule) continue;
    INFO(r.name);
    char exception[3];
    std::snprintf(exception, sizeof exception, "%02X", static_cast<int>(r.exception));
    CHECK(listed(static_cast<int>(r.value), r.name, exception));
    ++expected;
  }
  for (const auto& r : homing::kCheckRuleInfo) {
    if (r.value == homing::CheckRule::none) continue;
    INFO(r.name);
    CHECK(listed(registers::kRuleReasonBase + static_cast<int>(r.value), r.name, "03"));
    ++expected;
  }
  CHECK(rows.size() == expected);
  // Every combination rule says what to change, as the log does.
  for (const auto& r : homing::kCheckRuleInfo) {
    if (r.value == homing::CheckRule::none) continue;
    INFO(r.name);
    const std::string fix(homing::rule_fix(r.value));
    CHECK(fix.size() > 10);
    const std::string prefix = std::to_string(registers::kRuleReasonBase + static_cast<int>(r.value)) + ",";
    const auto row = std::find_if(rows.begin(), rows.end(), [&](const std::string& l) { return l.rfind(prefix, 0) == 0; });
    REQUIRE(row != rows.end());
    CHECK(row->find(fix) != std::string::npos);
  }
  // The register's value list is the same set of codes (plus 0, none).
  const auto* reg = registers::find_register("status.last_refusal_reason");
  REQUIRE(reg != nullptr);
  CHECK(reg->values.size() == expected + 1);
}

TEST_CASE("enums.csv holds every value of every enum and bitmask register") {
  const auto lines = lines_of(generated("enums.csv"));
  REQUIRE(!lines.empty());
  CHECK(lines[0] == "enum,value,name,text");
  const std::set<std::string> rows(lines.begin() + 1, lines.end());
  for (const registers::Register& r : registers::all_registers()) {
    if (r.values.empty()) continue;
    const auto list = std::find_if(registers::value_lists().begin(), registers::value_lists().end(),
                                   [&](const auto& l) { return l.values.data() == r.values.data(); });
    REQUIRE(list != registers::value_lists().end());
    for (const auto& v : r.values) {
      INFO(r.name() << " value " << v.value);
      const bool listed = std::any_of(rows.begin(), rows.end(), [&](const std::string& row) {
        return row.rfind(std::string(list->name) + "," + std::to_string(v.value) + "," + std::string(v.name), 0) == 0;
      });
      CHECK(listed);
    }
  }
}
