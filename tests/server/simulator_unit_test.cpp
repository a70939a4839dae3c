// The simulator unit (247) of the real homingd over Modbus/TCP (libmodbus):
// every acknowledged write holds and reads back, whatever the order and rate;
// a write that would move a moving carriage or its cams is refused with
// exception 06 and changes nothing, while faults strike at any moment; the simulated machine is wired from the settings (an
// external-commutator slave's carriage is moved by its master's output).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "daemon.hpp"
#include "homing/alarms.hpp"
#include "homing/sim/config.hpp"

using namespace e2e;

namespace {

constexpr const char* kAllAxes[] = {"x", "y", "z", "a", "b", "c"};

template <class E>
std::int64_t v(E e) {
  return static_cast<std::int64_t>(e);
}

std::string sim(const char* axis, const char* field) { return std::string("sim.") + axis + "." + field; }

// One write per simulator setting of every axis, each value different from
// the defaults and from the other axes, all valid together.
std::vector<std::pair<std::string, std::int64_t>> distinct_sim_values(std::int64_t salt) {
  std::vector<std::pair<std::string, std::int64_t>> w;
  for (std::int64_t k = 0; k < 6; ++k) {
    const char* a = kAllAxes[k];
    const std::int64_t n = k + 6 * salt;
    w.emplace_back(sim(a, "actual_position"), 100'000 + 1'111 * n);
    w.emplace_back(sim(a, "sensor_min"), -900'000 - 7 * n);
    w.emplace_back(sim(a, "sensor_max"), -100 - 3 * n);
    w.emplace_back(sim(a, "hysteresis"), 40 + n);
    w.emplace_back(sim(a, "noise"), 3 + n);
    w.emplace_back(sim(a, "bounce_ms"), 1 + n);
    w.emplace_back(sim(a, "sensor_nc"), n % 2);
    w.emplace_back(sim(a, "hard_stop_min"), -6'000 - 10 * n);
    w.emplace_back(sim(a, "hard_stop_max"), 900'000 + 10 * n);
    w.emplace_back(sim(a, "index_pitch"), 2'000 + n);
    w.emplace_back(sim(a, "index_offset"), 100 + n);
    w.emplace_back(sim(a, "absolute_offset"), -50'000 + 13 * n);
    w.emplace_back(sim(a, "fault"), 1 + n % 3);  // stuck active, stuck inactive, wire break
  }
  w.emplace_back("sim.seed", 4242 + salt);
  return w;
}

bool at_rest(Client& c) {
  for (const char* a : kAllAxes)
    if (c.read(std::string("axis.") + a + ".velocity") != 0) return false;
  return true;
}

}  // namespace

TEST_CASE("acknowledged simulator writes hold: many registers written back to back all read back") {
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto first = distinct_sim_values(1);
  for (const auto& [name, value] : first) {
    INFO(name << " = " << value);
    REQUIRE(c.write(name, value) == 0);
  }
  for (const auto& [name, value] : first) {
    INFO(name);
    CHECK(c.read(name) == value);
  }
  // Again in the reverse order with other values, each read back at once.
  auto second = distinct_sim_values(2);
  std::reverse(second.begin(), second.end());
  for (const auto& [name, value] : second) {
    INFO(name << " = " << value);
    REQUIRE(c.write(name, value) == 0);
    CHECK(c.read(name) == value);
  }
  for (const auto& [name, value] : second) {
    INFO(name);
    CHECK(c.read(name) == value);
  }
}

TEST_CASE("acknowledged simulator writes hold with two clients writing different axes at once") {
  Daemon d;
  const auto values = distinct_sim_values(3);
  auto writer = [&](bool even) {
    Client c = Client::tcp(d.port());
    int written = 0;
    for (std::size_t i = 0; i < values.size(); ++i) {
      const auto& [name, value] = values[i];
      if (name == "sim.seed") continue;
      const bool axis_even = (name[4] == 'x' || name[4] == 'z' || name[4] == 'b');
      if (axis_even != even) continue;
      if (c.write(name, value) == 0) ++written;
    }
    return written;
  };
  int a = 0, b = 0;
  std::thread t([&] { a = writer(true); });
  b = writer(false);
  t.join();
  CHECK(a == 39);
  CHECK(b == 39);
  Client c = Client::tcp(d.port());
  for (const auto& [name, value] : values) {
    if (name == "sim.seed") continue;
    INFO(name);
    CHECK(c.read(name) == value);
  }
}

TEST_CASE("a simulator write that moves a moving carriage or its cams is refused with exception 06 and changes nothing") {
  Daemon d;
  Client c = Client::tcp(d.port());
  c.set("sim.z.actual_position", um(200));
  // Jog Z (allowed at reduced speed before homing): its carriage moves while the coil is held.
  REQUIRE(c.write("cmd.jog_plus.z", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("axis.z.velocity") != 0; }, 2s));
  std::map<std::string, std::int64_t> before;
  for (const char* f : {"sensor_min", "sensor_max", "hard_stop_min", "hard_stop_max", "index_pitch", "index_offset",
                        "absolute_offset", "drive_home_position"})
    before[sim("z", f)] = c.read(sim("z", f));
  CHECK(c.write("sim.z.sensor_min", um(-20)) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  CHECK(c.write("sim.z.hard_stop_max", um(500)) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  CHECK(c.write("sim.z.hard_stop_min", um(-7)) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  CHECK(c.write("sim.z.index_pitch", um(4)) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  CHECK(c.write("sim.z.index_offset", um(1)) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  CHECK(c.write("sim.z.absolute_offset", um(1)) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  CHECK(c.write("sim.z.drive_home_position", um(3)) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  CHECK(c.write("sim.z.actual_position", um(50)) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  // A request covering two settings of the moving axis: nothing of it is applied.
  const auto& smin = reg("sim.z.sensor_min");
  REQUIRE(reg("sim.z.sensor_max").address == smin.address + 2);
  const std::uint16_t words[4] = {0xFFFF, 0xFF00, 0, 5};
  c.use_unit(247);
  CHECK(modbus_write_registers(c.ctx(), smin.address, 4, words) == -1);
  CHECK(exception_of(errno) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  c.use_unit(1);
  const std::int64_t z_moving = c.read("sim.z.actual_position");
  for (const auto& [name, value] : before) {
    INFO(name);
    CHECK(c.read(name) == value);
  }
  // What strikes a moving carriage in a real machine is taken at any moment:
  // noise, wear, bounce, wiring, a fault, lost steps.
  CHECK(c.write("sim.z.noise", 7) == 0);
  CHECK(c.read("sim.z.noise") == 7);
  CHECK(c.write("sim.z.hysteresis", 77) == 0);
  CHECK(c.read("sim.z.hysteresis") == 77);
  CHECK(c.write("sim.z.bounce_ms", 3) == 0);
  CHECK(c.read("sim.z.bounce_ms") == 3);
  CHECK(c.write("sim.z.lose_steps", um(3)) == 0);
  // Axes at rest and the machine-wide knobs are still written.
  CHECK(c.write("sim.c.noise", 9) == 0);
  CHECK(c.read("sim.c.noise") == 9);
  CHECK(c.write("sim.seed", 99) == 0);
  REQUIRE(c.write("cmd.jog_plus.z", 0) == 0);
  REQUIRE(wait_until([&] { return at_rest(c); }, 5s));
  CHECK(c.read("sim.z.actual_position") > z_moving);  // it went on jogging, not placed at 50
  // At rest the geometry writes are taken.
  CHECK(c.write("sim.z.sensor_min", um(-20)) == 0);
  CHECK(c.read("sim.z.sensor_min") == um(-20));
  CHECK(c.write("sim.z.actual_position", um(50)) == 0);
  CHECK(c.read("sim.z.actual_position") == um(50));
}

TEST_CASE("a fault written to the simulator while an axis homes strikes mid-cycle with the alarm it causes") {
  Daemon d({.time_scale = 2});
  Client c = Client::tcp(d.port());
  c.set("axis.x.mode", 0);
  c.set("axis.y.mode", 0);
  c.set("sequence.step1", 0b100);
  c.set("sequence.step2", 0);
  c.set("sim.z.actual_position", um(150));
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  // Z seeks toward its cam (150 mm away): the drive fails while it moves.
  REQUIRE(wait_until([&] { return c.read("axis.z.velocity") != 0; }, 5s));
  CHECK(c.read("status.homing") == 1);
  REQUIRE(c.write("sim.z.fault", v(homing::sim::Fault::drive_fault)) == 0);
  REQUIRE(wait_until([&] { return c.read("status.alarm") != 0; }, 5s));
  CHECK(c.read("axis.z.alarm") == v(homing::AlarmCode::drive_fault));
  CHECK(c.read("axis.z.homed") == 0);
  REQUIRE(wait_until([&] { return at_rest(c); }, 5s));
  // The fault cleared, the alarm resets and the axis homes.
  REQUIRE(c.write("sim.z.fault", 0) == 0);
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 0; }, 2s));
  c.set("sim.z.actual_position", um(10));
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("axis.z.homed") == 1 || c.read("status.alarm") != 0; }, 30s));
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("axis.z.homed") == 1);
}

TEST_CASE("the simulator wires an external-commutator slave to its master's output from the settings") {
  TempDir dir;
  const std::string db = dir.file("settings.db");
  {
    Daemon d({.db = db});
    Client c = Client::tcp(d.port());
    for (const char* a : kAllAxes) CHECK(c.read(sim(a, "driven_by")) == 0);
    // axis.y.slave_of = 1 (X) and slave_mode = 1 (external commutator) in one request.
    const auto& slave_of = reg("axis.y.slave_of");
    REQUIRE(reg("axis.y.slave_mode").address == slave_of.address + 1);
    const std::uint16_t words[2] = {1, 1};
    c.use_unit(1);
    REQUIRE(modbus_write_registers(c.ctx(), slave_of.address, 2, words) == 2);
    REQUIRE(wait_until([&] { return c.read("sim.y.driven_by") == 1; }, 2s));
    CHECK(c.read("sim.x.driven_by") == 0);

    // Jogging X moves both carriages by the same distance.
    const std::int64_t x0 = c.read("sim.x.actual_position"), y0 = c.read("sim.y.actual_position");
    REQUIRE(c.write("cmd.jog_plus.x", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("sim.x.actual_position") > x0 + 1000; }, 5s));
    // The slave's carriage moves with X's output: its cams are busy too.
    CHECK(c.write("sim.y.sensor_max", 5) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
    REQUIRE(c.write("cmd.jog_plus.x", 0) == 0);
    REQUIRE(wait_until([&] { return at_rest(c); }, 5s));
    const std::int64_t dx = c.read("sim.x.actual_position") - x0, dy = c.read("sim.y.actual_position") - y0;
    CHECK(dx > 1000);
    CHECK(std::llabs(dy - dx) <= 1);  // µm rounding of two positions
  }
  {
    // At start the wiring comes from the stored settings, with no option.
    Daemon d({.db = db});
    Client c = Client::tcp(d.port());
    CHECK(c.read("sim.y.driven_by") == 1);
    // Back to its own output: the wiring follows the change.
    REQUIRE(c.write("axis.y.slave_mode", 0) == 0);
    REQUIRE(wait_until([&] { return c.read("sim.y.driven_by") == 0; }, 2s));
    CHECK(c.read("axis.y.slave_of") == 1);
  }
}
