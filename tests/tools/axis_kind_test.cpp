// A linear gantry slave on A, set up over Modbus as a machine builder would:
// homingctl get, check, export and maps name its values in mm, a slave in its
// master's unit; the settings file makes the same tag files without a module.
#include <catch2/catch.hpp>

#include "check.hpp"
#include "registers/defaults.hpp"
#include "settings_io.hpp"
#include "tools_helpers.hpp"

using namespace tools_test;

namespace {

bool has_line(const std::string& text, const std::string& line) {
  return text.find("\n" + line + "\n") != std::string::npos;
}

// The line of `text` that starts with `start` ("" when none).
std::string line_of(const std::string& text, const std::string& start) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(start, 0) == 0) return line;
  return "";
}

// A homes on a switch as the second motor of Y, linear; a value typed with
// its unit in the same command is in the unit of the kind it sets.
const std::vector<std::string> kLinearASlaveOfY{"axis.a.mode=switch_release", "axis.a.slave_of=y",
                                                "axis.a.kind=linear", "axis.a.max_misalignment=2mm"};

homing::Settings linear_a_slave_of_y() {
  homing::Settings s = registers::default_settings();
  s.axes[3].mode = homing::HomingMode::switch_release;
  s.axes[3].slave_of = 2;
  s.axes[3].kind = homing::AxisKind::linear;
  return s;
}

void check_kepware_in_mm(const std::string& kepware) {
  for (const char* name : {"axis.a.max_misalignment,", "axis.a.pull_off,", "axis.a.position,"}) {
    const std::string row = line_of(kepware, name);
    INFO(row);
    CHECK_THAT(row, Catch::Contains(",mm,") && !Catch::Contains("deg"));
  }
  CHECK_THAT(line_of(kepware, "axis.a.seek_feedrate,"), Catch::Contains(",mm/min,"));
  CHECK_THAT(line_of(kepware, "axis.b.seek_feedrate,"), Catch::Contains(",deg/min,"));
}

}  // namespace

TEST_CASE("homingctl check renders a linear gantry slave on A in mm") {
  const homingctl::CheckReport r = homingctl::check_settings(linear_a_slave_of_y(), {});
  const std::string text = homingctl::render_check(r);
  INFO(text);
  const std::string a = line_of(text, "A ");
  CHECK_THAT(a, Catch::Contains(" mm ") && !Catch::Contains("deg"));
  CHECK_THAT(text, Catch::Contains("the trigger cam must be longer than the stop distance 0.278 mm"));
  CHECK(homingctl::check_json(r)["axes"][3]["unit"] == "mm");
  CHECK(homingctl::check_json(r)["axes"][4]["unit"] == "deg");  // B stays rotary
}

TEST_CASE("the settings file of a linear gantry slave on A writes its values in mm") {
  const std::string text = homingctl::settings_file_text(registers::settings_to_raw(linear_a_slave_of_y()), "a test", 0);
  INFO(text);
  CHECK(has_line(text, "axis.a.kind = \"linear\""));
  CHECK(has_line(text, "axis.a.max_misalignment = 2.0  # mm"));
  CHECK(has_line(text, "axis.a.seek_feedrate = 1000.0  # mm/min"));
  CHECK(has_line(text, "axis.a.acceleration = 500.0  # mm/s²"));
  CHECK(has_line(text, "axis.b.pull_off = 1.0  # deg"));  // B stays rotary
}

TEST_CASE("a linear gantry slave on A set over Modbus reads mm in get, check, export and the map files") {
  TempDir dir;
  Daemon d;
  std::vector<std::string> set{"set"};
  set.insert(set.end(), kLinearASlaveOfY.begin(), kLinearASlaveOfY.end());
  auto r = ctl(d, set);
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
  }
  CHECK_THAT(r.out, Catch::Contains("axis.a.kind: rotary -> linear"));

  // B is still rotary: a length typed in mm is not its unit.
  r = ctl(d, {"set", "axis.b.pull_off=2mm"});
  {
    SHOW(r);
    CHECK(r.code() != 0);
    CHECK_THAT(r.err, Catch::Contains("axis.b.pull_off = '2mm'") && Catch::Contains("deg"));
  }

  r = ctl(d, {"get", "axis.a.pull_off", "axis.a.seek_feedrate", "axis.b.pull_off"});
  {
    SHOW(r);
    CHECK(r.out == "axis.a.pull_off = 1 mm\naxis.a.seek_feedrate = 1000 mm/min\naxis.b.pull_off = 1 deg\n");
  }

  r = ctl(d, {"check"});
  {
    SHOW(r);
    CHECK_THAT(line_of(r.out, "A "), Catch::Contains(" mm ") && !Catch::Contains("deg"));
  }

  // Writing rotary to X: refused with the reason, nothing written.
  r = ctl(d, {"set", "axis.x.kind=rotary"});
  {
    SHOW(r);
    CHECK(r.code() != 0);
    CHECK_THAT(r.err, Catch::Contains("axis.x.kind = rotary: X is a linear axis (mm); only A, B and C can be rotary"));
  }

  const std::string file = dir.file("machine.toml");
  r = ctl(d, {"export", file});
  REQUIRE(r.code() == 0);
  const std::string text = read_file(file);
  {
    INFO(text);
    CHECK(has_line(text, "axis.a.max_misalignment = 2.0  # mm"));
    CHECK(has_line(text, "axis.a.seek_feedrate = 1000.0  # mm/min"));
    CHECK(has_line(text, "axis.x.kind = \"linear\""));
  }

  r = ctl(d, {"maps", dir.file("maps")});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
  }
  check_kepware_in_mm(read_file(dir.file("maps/kepware_module.csv")));
  const auto ignition = nlohmann::json::parse(read_file(dir.file("maps/ignition_tags.json")));
  bool found = false;
  for (const auto& folder : ignition["tags"])
    if (folder["name"] == "module")
      for (const auto& group : folder["tags"])
        if (group["name"] == "axis")
          for (const auto& axis : group["tags"])
            if (axis["name"] == "a")
              for (const auto& tag : axis["tags"])
                if (tag["name"] == "max_misalignment") {
                  CHECK(tag["engUnit"] == "mm");
                  found = true;
                }
  CHECK(found);
  const std::string ha = read_file(dir.file("maps/home_assistant_modbus.yaml"));
  const auto at = ha.find("name: \"homing axis.a.max_misalignment\"");
  REQUIRE(at != std::string::npos);
  CHECK_THAT(ha.substr(at, ha.find("- name:", at) - at), Catch::Contains("unit_of_measurement: \"mm\""));

  // The same files from the settings file, with no module.
  r = ctl_plain({"maps", dir.file("from_file"), "--from", file});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
  }
  check_kepware_in_mm(read_file(dir.file("from_file/kepware_module.csv")));
}

// The commissioning guide's gantry: B set linear, then its simulated switch placed.
TEST_CASE("homingctl set echoes a simulated carriage's value in the unit of its axis kind, as get reads it") {
  Daemon d;
  REQUIRE(ctl(d, {"set", "axis.b.kind=linear"}).code() == 0);
  auto r = ctl(d, {"set", "sim.b.sensor_max=0.3", "sim.c.sensor_max=0.2"});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
    CHECK(has_line("\n" + r.out, "sim.b.sensor_max = 0.3 mm"));
    CHECK(has_line("\n" + r.out, "sim.c.sensor_max = 0.2 deg"));  // C stays rotary
  }
  r = ctl(d, {"get", "sim.b.sensor_max"});
  CHECK(r.out == "sim.b.sensor_max = 0.3 mm\n");
}
