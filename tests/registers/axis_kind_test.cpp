// axis.<a>.kind: one row of the table, X Y Z linear only (refused at write
// time with its own reason), A B C rotary by default; the unit of every value
// of an axis follows the kind it moves with, in the maps too.
#include <catch2/catch.hpp>

#include <sstream>
#include <string>

#include "homing/settings_check.hpp"
#include "registers/defaults.hpp"
#include "registers/errors.hpp"
#include "registers/exports.hpp"
#include "registers/lookup.hpp"
#include "registers/validate.hpp"
#include "tests/support/named_registers.hpp"

using namespace registers;

namespace {
using test_support::reg;

auto write_one(const char* name, std::int64_t raw, const homing::Settings& s) {
  const Register& r = reg(name);
  std::vector<std::uint16_t> w(r.words());
  encode_words(r, raw, WordOrder::high_first, w);
  return validate_write(r.table, r.address, w, WordOrder::high_first, s, default_host_registers());
}

// A is the second motor of Y, linear, as a machine builder sets it.
homing::Settings linear_a_slave_of_y() {
  homing::Settings s = default_settings();
  s.axes[3].mode = homing::HomingMode::switch_release;
  s.axes[3].slave_of = 2;
  s.axes[3].kind = homing::AxisKind::linear;
  return s;
}

// The line of `file` that starts with `start` ("" when none).
std::string line_of(const std::string& file, const std::string& start) {
  std::istringstream in(file);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(start, 0) == 0) return line;
  return "";
}

std::string generated(const MapUnits& units, const std::string& name) {
  for (const auto& f : generate_hmi_maps(units))
    if (f.name == name) return f.content;
  FAIL("no generated file " << name);
  return "";
}

}  // namespace

TEST_CASE("axis.<a>.kind defaults: X Y Z linear, A B C rotary, as before the setting existed") {
  const homing::Settings s = default_settings();
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const Register& r = reg(std::string("axis.") + std::string(homing::kAxisLetters[a]) + ".kind");
    INFO(r.name());
    CHECK(r.persisted);
    CHECK(r.default_raw == (a < 3 ? 0 : 1));
    CHECK(value_name(r, 0) == "linear");
    CHECK(value_name(r, 1) == "rotary");
    CHECK(s.axes[a].kind == (a < 3 ? homing::AxisKind::linear : homing::AxisKind::rotary));
  }
  CHECK(reg("axis.a.max_seek_travel").unit_text(kinds_of(s)) == "deg");
  CHECK(reg("axis.x.max_seek_travel").unit_text(kinds_of(s)) == "mm");
}

TEST_CASE("writing rotary to X is refused with the rule kind_linear_only, nothing written") {
  const homing::Settings s = default_settings();
  const auto refused = write_one("axis.x.kind", 1, s);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ExceptionCode::illegal_data_value);
  CHECK(refused.error().reason == RefusalReason::rule);
  CHECK(refused.error().rule == homing::CheckRule::kind_linear_only);
  CHECK(refused.error().address == reg("axis.x.kind").address);
  CHECK_THAT(refused.error().message,
             Catch::StartsWith("axis.x.kind = rotary: X is a linear axis (mm); only A, B and C can be rotary") &&
                 Catch::EndsWith("nothing was written"));
  for (const char* name : {"axis.y.kind", "axis.z.kind"}) CHECK_FALSE(write_one(name, 1, s));
  // A, B and C take either.
  CHECK(write_one("axis.a.kind", 0, s));
  CHECK(write_one("axis.c.kind", 0, s));
  // An import holding a rotary Z is refused too.
  auto values = settings_to_raw(s);
  values["axis.z.kind"] = 1;
  const auto r = validate_settings_map(values);
  REQUIRE(r);
  CHECK(r->rule == homing::CheckRule::kind_linear_only);
}

TEST_CASE("values of a linear gantry slave on A are in mm in write messages") {
  const homing::Settings s = linear_a_slave_of_y();
  REQUIRE_FALSE(homing::check_axis(s, 3));
  const auto refused = write_one("axis.a.switch_compensation", 2500, s);  // alone beyond max_misalignment
  REQUIRE_FALSE(refused);
  CHECK_THAT(refused.error().message, Catch::Contains("is 2.5 mm, not less than axis.a.max_misalignment = 2 mm"));
  const auto too_far = write_one("axis.a.max_misalignment", 200'000'000, s);
  REQUIRE_FALSE(too_far);
  CHECK_THAT(too_far.error().message, Catch::Contains("200000 mm is outside its range 0..100000 mm"));
}

TEST_CASE("the committed maps name A B C values in deg and say that the unit follows axis.<a>.kind") {
  const MapUnits new_module;
  const std::string kepware = generated(new_module, "kepware_module.csv");
  const std::string a_row = line_of(kepware, "axis.a.max_misalignment,");
  INFO(a_row);
  CHECK_THAT(a_row, Catch::Contains(",deg,") && Catch::Contains("[deg: axis.a.kind = rotary (default); mm when linear]"));
  const std::string x_row = line_of(kepware, "axis.x.max_misalignment,");
  CHECK_THAT(x_row, Catch::Contains(",mm,") && !Catch::Contains("axis.x.kind"));
  CHECK_THAT(line_of(generated(new_module, "registers.csv"), "axis.c.seek_feedrate,"),
             Catch::Contains(",deg/min,") && Catch::Contains("mm/min when linear"));
}

TEST_CASE("maps made for a linear gantry slave on A name mm in every tag file") {
  const MapUnits units{kinds_of(linear_a_slave_of_y()), "machine.toml"};
  const std::string kepware = generated(units, "kepware_module.csv");
  for (const char* name : {"axis.a.max_misalignment,", "axis.a.position,", "axis.a.alarm_value,"}) {
    const std::string row = line_of(kepware, name);
    INFO(row);
    CHECK_THAT(row, Catch::Contains(",mm,") && !Catch::Contains("deg"));
  }
  CHECK_THAT(line_of(kepware, "axis.a.seek_feedrate,"), Catch::Contains(",mm/min,"));
  CHECK_THAT(line_of(kepware, "axis.b.seek_feedrate,"), Catch::Contains(",deg/min,"));  // B stays rotary
  CHECK_THAT(line_of(generated(units, "kepware_simulator.csv"), "sim.a.actual_position,"), Catch::Contains(",mm,"));
  CHECK_THAT(line_of(generated(units, "registers.csv"), "axis.a.pull_off,"), Catch::Contains(",mm,"));

  const std::string ignition = generated(units, "ignition_tags.json");
  const auto at = ignition.find("]1.HRI" + std::to_string(reg("axis.a.max_misalignment").address + 1) + "\"");
  REQUIRE(at != std::string::npos);
  const std::string tag = ignition.substr(at, ignition.find('}', at) - at);
  INFO(tag);
  CHECK_THAT(tag, Catch::Contains("\"engUnit\": \"mm\""));

  const std::string ha = generated(units, "home_assistant_modbus.yaml");
  const auto entity = ha.find("name: \"homing axis.a.max_misalignment\"");
  REQUIRE(entity != std::string::npos);
  const std::string block = ha.substr(entity, ha.find("- name:", entity) - entity);
  INFO(block);
  CHECK_THAT(block, Catch::Contains("unit_of_measurement: \"mm\""));
  CHECK_THAT(ha.substr(0, ha.find('\n')),
             Catch::Contains("homingctl maps from machine.toml") && Catch::Contains("A linear"));
  CHECK_THAT(generated(units, "registers.md"), Catch::Contains("on the rotary axes of this machine (B, C) read deg"));
}
