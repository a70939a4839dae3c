// The settings file in engineering units and value names: what homingctl
// export writes, that a fresh module imports it to the same file, that every
// setting's spelling reads back exactly, and that a bad file names each bad
// value and changes nothing.
#include <catch2/catch.hpp>

#include <fstream>

#include "persistence/settings_file.hpp"
#include "registers/defaults.hpp"
#include "registers/lookup.hpp"
#include "registers/settings_file_values.hpp"
#include "settings_io.hpp"
#include "tools_helpers.hpp"

using namespace tools_test;

namespace {

const persistence::SettingsFileCodec kCodec{registers::file_value_text, registers::raw_of_file_value};

std::string from_format(const std::string& text) { return text.substr(text.find("format =")); }

bool has_line(const std::string& text, const std::string& line) {
  return text.find("\n" + line + "\n") != std::string::npos;
}

// Every setting at the value `pick` gives it.
template <class Pick>
std::map<std::string, std::int64_t> every_setting(Pick pick) {
  std::map<std::string, std::int64_t> out;
  for (const auto& r : registers::all_registers())
    if (r.persisted) out[r.name()] = pick(r);
  return out;
}

}  // namespace

TEST_CASE("every setting spelled in engineering units reads back to the same raw value") {
  TempDir dir;
  const std::string file = dir.file("all.toml");
  using registers::Register;
  for (const auto& [what, values] : std::vector<std::pair<std::string, std::map<std::string, std::int64_t>>>{
           {"min", every_setting([](const Register& r) { return r.min; })},
           {"max", every_setting([](const Register& r) { return r.max; })},
           {"default", every_setting([](const Register& r) { return r.default_raw; })},
           {"odd", every_setting([](const Register& r) { return r.min + (r.max - r.min) / 7 + 1; })}}) {
    INFO(what);
    std::ofstream(file) << persistence::settings_file_text(values, "test", 0, &kCodec);
    const auto parsed = persistence::read_settings_file(file);
    REQUIRE(parsed);
    CHECK(parsed->format_version == persistence::kEngineeringFormatVersion);
    const auto back = persistence::raw_values(file, *parsed, &kCodec);
    INFO(read_file(file));
    REQUIRE(back);
    CHECK(*back == values);
  }
}

TEST_CASE("a value that does not fit its setting is named with the value and the rule") {
  using registers::raw_of_file_value;
  auto refusal = [](const std::string& name, const registers::FileValue& v) {
    auto r = raw_of_file_value(name, v);
    REQUIRE_FALSE(r);
    return r.error();
  };
  CHECK(raw_of_file_value("axis.x.direction", std::string("positive")) == 1);
  CHECK(raw_of_file_value("axis.x.pull_off", 2.25) == 2250);
  CHECK(raw_of_file_value("axis.x.pull_off", std::int64_t{3}) == 3000);  // a whole number of mm
  CHECK(raw_of_file_value("axis.x.seek_feedrate", std::string("1200 mm/min")) == 1200);
  CHECK(raw_of_file_value("axis.x.sensor_nc", true) == 1);
  CHECK(raw_of_file_value("sequence.step2", std::string("x+y")) == 3);

  const auto direction = refusal("axis.x.direction", std::string("sideways"));
  CHECK_THAT(direction, Catch::Contains("axis.x.direction") && Catch::Contains("sideways") &&
                            Catch::Contains("negative (0), positive (1)"));
  const auto fine = refusal("axis.x.pull_off", 2.0005);
  CHECK_THAT(fine, Catch::Contains("axis.x.pull_off") && Catch::Contains("2.0005") && Catch::Contains("step of 0.001"));
  const auto range = refusal("axis.x.seek_feedrate", 90000.0);
  CHECK_THAT(range, Catch::Contains("axis.x.seek_feedrate") && Catch::Contains("90000") &&
                        Catch::Contains("out of range") && Catch::Contains("60000 mm/min"));
  const auto flag = refusal("axis.y.mode", true);
  CHECK_THAT(flag, Catch::Contains("axis.y.mode = true") && Catch::Contains("for flags"));
  const auto number = refusal("axis.x.direction", 1.5);
  CHECK_THAT(number, Catch::Contains("axis.x.direction = 1.5") && Catch::Contains("positive"));
  CHECK_THAT(refusal("axis.q.mode", std::int64_t{1}), Catch::Contains("not a setting"));
}

TEST_CASE("homingctl export writes engineering units and value names, and a fresh module imports it to the same "
          "export") {
  TempDir dir;
  const std::string first = dir.file("first.toml"), second = dir.file("second.toml");
  {
    Daemon a;
    auto r = ctl(a, {"set", "axis.x.seek_feedrate=1500", "axis.x.direction=positive",
                     "global.allowed_without_homing=jog_reduced", "axis.x.pull_off=2.25", "axis.y.home_position=-12.5",
                     "axis.a.seek_feedrate=3600", "global.alarm_clears_homed=off", "sequence.step1=x+y",
                     "global.history_max_rows=5000", "axis.x.debounce_ms=5"});
    {
      SHOW(r);
      REQUIRE(r.code() == 0);
    }
    r = ctl(a, {"export", first});
    REQUIRE(r.code() == 0);
  }
  const std::string text = read_file(first);
  INFO(text);
  CHECK(text.find("format_version = 2\n") != std::string::npos);
  CHECK(has_line(text, "axis.x.seek_feedrate = 1500.0  # mm/min"));
  CHECK(has_line(text, "axis.x.direction = \"positive\""));
  CHECK(has_line(text, "global.allowed_without_homing = \"jog_reduced\""));
  CHECK(has_line(text, "axis.x.pull_off = 2.25  # mm"));
  CHECK(has_line(text, "axis.y.home_position = -12.5  # mm"));
  CHECK(has_line(text, "axis.a.seek_feedrate = 3600.0  # deg/min"));
  CHECK(has_line(text, "axis.a.pull_off = 1.0  # deg"));
  CHECK(has_line(text, "global.alarm_clears_homed = false"));
  CHECK(has_line(text, "sequence.step1 = \"x+y\""));
  CHECK(has_line(text, "global.history_max_rows = 5000"));
  CHECK(has_line(text, "axis.x.debounce_ms = 5.0  # ms"));
  CHECK(has_line(text, "axis.x.mode = \"switch_release\""));
  CHECK(text.find("2250") == std::string::npos);  // no raw µm anywhere

  Daemon b;  // fresh database: defaults
  Client c = Client::tcp(b.port());
  CHECK(c.read("axis.x.pull_off") == 1000);
  auto r = ctl(b, {"import", first});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
  }
  CHECK(c.read("axis.x.pull_off") == 2250);
  CHECK(c.read("axis.x.direction") == 1);
  CHECK(c.read("axis.y.home_position") == -12500);
  CHECK(c.read("sequence.step1") == 3);
  REQUIRE(ctl(b, {"export", second}).code() == 0);
  CHECK(from_format(read_file(second)) == from_format(text));
}

TEST_CASE("homingctl import of a bad file names each bad key, value and rule and changes no register") {
  Daemon d;
  TempDir dir;
  Client c = Client::tcp(d.port());
  const auto before = holding_snapshot(c);
  const std::string head = "format = \"homing-module-settings\"\nformat_version = 2\n\n[settings]\n";

  const std::string bad = dir.file("bad.toml");
  std::ofstream(bad) << head
                     << "axis.x.latch_feedrate = 50.0  # mm/min\n"  // line 5, valid: must not be written either
                        "axis.x.direction = \"sideways\"\n"
                        "axis.x.pull_off = 2.0005  # mm\n"
                        "axis.x.seek_feedrate = 90000.0\n"
                        "axis.y.mode = true\n";
  auto r = ctl(d, {"import", bad});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("4 values cannot be imported; nothing was imported") != std::string::npos);
    CHECK(r.err.find(bad + ":6: axis.x.direction = 'sideways'") != std::string::npos);
    CHECK(r.err.find("accepted: negative (0), positive (1)") != std::string::npos);
    CHECK(r.err.find(bad + ":7: axis.x.pull_off = '2.0005': finer than the register's step of 0.001 mm") !=
          std::string::npos);
    CHECK(r.err.find(bad + ":8: axis.x.seek_feedrate = '90000': out of range; accepted: 1 mm/min .. 60000 mm/min") !=
          std::string::npos);
    CHECK(r.err.find(bad + ":9: axis.y.mode = true: true/false is for flags") != std::string::npos);
  }
  CHECK(holding_snapshot(c) == before);

  // Each value fits, but together they break a rule: named with its line and value.
  const std::string rule = dir.file("rule.toml");
  std::ofstream(rule) << head
                      << "axis.x.max_stop_distance = 10.0  # mm\n"
                         "axis.x.seek_feedrate = 20000.0  # mm/min\n";
  r = ctl(d, {"import", rule});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find(rule + ":5: axis.x.max_stop_distance = 10.0: ") != std::string::npos);
    CHECK(r.err.find("nothing was written") != std::string::npos);
  }
  CHECK(holding_snapshot(c) == before);

  // An unknown name in an engineering file.
  const std::string unknown = dir.file("unknown.toml");
  std::ofstream(unknown) << head << "axis.x.pull_off = 2.0  # mm\naxis.x.nonsense = \"on\"\n";
  r = ctl(d, {"import", unknown});
  CHECK(r.code() == 1);
  CHECK(r.err.find(unknown + ":6: unknown register 'axis.x.nonsense'") != std::string::npos);
  CHECK(holding_snapshot(c) == before);
}
