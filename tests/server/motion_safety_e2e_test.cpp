// The multi-axis motion-safety rules, as a new user meets them: the real
// homingd over Modbus/TCP (libmodbus), configured over the wire and checked
// against the simulator unit's truth.
#include <catch2/catch.hpp>

#include <cmath>

#include "daemon.hpp"
#include "homing/status.hpp"
#include "registers/lookup.hpp"

using namespace e2e;

namespace {

int state_of(Client& c) { return static_cast<int>(c.read("status.state")); }
int result_of(Client& c) { return static_cast<int>(c.read("status.last_command_result")); }
bool settled(Client& c) {
  const int s = state_of(c);
  return s == static_cast<int>(homing::MachineState::homed) || s == static_cast<int>(homing::MachineState::alarm);
}

// Polls until the cycle ends (bounded), recording the largest change of the
// carriages' relative position Y - X seen by the simulator.
// Y's position relative to X, both taken in one request: two separate reads
// would see the carriages at different moments and report racking that
// never happened.
double y_relative_to_x(Client& c) {
  const auto p = c.read_together({"sim.x.actual_position", "sim.y.actual_position"});
  return static_cast<double>(p[1] - p[0]) / 1000.0;
}

double home_all_watching_rack(Client& c, std::chrono::milliseconds timeout = 30s) {
  const double rel0 = y_relative_to_x(c);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  double worst = 0;
  const auto deadline = Clock::now() + timeout;
  int n = 0;
  while (Clock::now() < deadline && n++ < 20000) {
    const double rel = y_relative_to_x(c);
    worst = std::max(worst, std::abs(rel - rel0));
    if (settled(c) && c.read("axis.x.velocity") == 0 && c.read("axis.y.velocity") == 0) break;
    std::this_thread::sleep_for(2ms);
  }
  return worst;
}

// Y as the software-slaved second motor of X; only X and Y home (Z disabled).
void make_gantry(Client& c, int slave_mode) {
  c.set("axis.z.mode", 0);
  c.set("sequence.step1", 0b011);
  c.set("sequence.step2", 0);
  c.set("axis.y.slave_mode", slave_mode);
  c.set("axis.y.slave_of", 1);
  c.set("sim.x.noise", 0);
  c.set("sim.y.noise", 0);
}

}  // namespace

TEST_CASE("over Modbus a slave whose own direction, feedrates and mode differ homes square, never racking past its limit") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  // Written before Y becomes a slave: its own values, not used while it is one.
  c.set("axis.y.direction", 1);
  c.set("axis.y.seek_feedrate", 3000);
  c.set("axis.y.latch_feedrate", 700);
  make_gantry(c, 0);
  // Once it is a slave, a change to one of them is refused, naming X's register to write instead.
  CHECK(c.write("axis.y.seek_feedrate", 2500) == 3);
  CHECK(c.read("status.last_refused_register") == registers::find_register("axis.x.seek_feedrate")->address);
  CHECK(c.read("axis.y.seek_feedrate") == 3000);
  c.set("axis.y.mode", 3);
  c.set("axis.y.acceleration", 2000);
  c.set("sim.y.sensor_max", um(0.8));  // the slave's switch sits 0.8 mm further out
  REQUIRE(c.read_mm("sim.y.sensor_max") == Approx(0.8));
  const double worst = home_all_watching_rack(c);
  REQUIRE(state_of(c) == static_cast<int>(homing::MachineState::homed));
  CHECK(worst <= 2.0);
  // Square by the sensors: each carriage pulled off its own release edge.
  const double hyst = c.read_mm("sim.x.hysteresis");
  CHECK(c.read_mm("sim.x.actual_position") == Approx(0 + hyst + c.read_mm("axis.x.pull_off")).margin(0.01));
  CHECK(c.read_mm("sim.y.actual_position") == Approx(0.8 + hyst + c.read_mm("axis.y.pull_off")).margin(0.01));
  CHECK(c.read("axis.y.position") == c.read("axis.x.position"));
}

TEST_CASE("over Modbus a gantry whose slave sensor is dead stops within max_misalignment") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  make_gantry(c, 0);
  c.set("sim.y.fault", 2);  // stuck inactive
  const double worst = home_all_watching_rack(c);
  CHECK(state_of(c) == static_cast<int>(homing::MachineState::alarm));
  CHECK(c.read("axis.y.alarm") == static_cast<int>(homing::AlarmCode::misalignment));
  CHECK(worst <= 2.0 + 0.05);
}

TEST_CASE("over Modbus the external-commutator gantry homes square on one output") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  make_gantry(c, 1);
  c.set("sim.y.sensor_max", um(0.6));
  const double worst = home_all_watching_rack(c);
  REQUIRE(state_of(c) == static_cast<int>(homing::MachineState::homed));
  CHECK(worst <= 2.0);
  const double hyst = c.read_mm("sim.x.hysteresis");
  const double pull = c.read_mm("axis.x.pull_off");
  CHECK(c.read_mm("sim.x.actual_position") == Approx(0 + hyst + pull).margin(0.01));
  CHECK(c.read_mm("sim.y.actual_position") == Approx(0.6 + hyst + pull).margin(0.01));
}

TEST_CASE("over Modbus a disabled axis or a slave's slave cannot be named as slave: exception 03, nothing written") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  c.set("axis.c.mode", 0);
  CHECK(c.write("axis.c.slave_of", 1) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.read("axis.c.slave_of") == 0);
  c.set("axis.y.slave_of", 1);
  CHECK(c.write("axis.z.slave_of", 2) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.read("axis.z.slave_of") == 0);
  CHECK(c.write("axis.x.mode", 0) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);  // X is Y's master
  CHECK(c.read("axis.x.mode") == 2);
}

TEST_CASE("over Modbus a hard-limit trip is recovered by reset and a jog away, with alarm_clears_homed off") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  c.set("axis.y.mode", 0);
  c.set("axis.z.mode", 0);
  c.set("sequence.step1", 0b001);
  c.set("sequence.step2", 0);
  c.set("global.alarm_clears_homed", 0);
  c.set("axis.x.shared_limit", 1);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  const auto deadline = Clock::now() + 20s;
  while (Clock::now() < deadline && !settled(c)) std::this_thread::sleep_for(5ms);
  REQUIRE(state_of(c) == static_cast<int>(homing::MachineState::homed));
  REQUIRE(c.write("cmd.jog_minus.x", 1) == 0);  // toward the sensor
  const auto trip = Clock::now() + 20s;
  while (Clock::now() < trip && c.read("axis.x.alarm") == 0) std::this_thread::sleep_for(5ms);
  REQUIRE(c.write("cmd.jog_minus.x", 0) == 0);
  REQUIRE(c.read("axis.x.alarm") == static_cast<int>(homing::AlarmCode::hard_limit));
  // The trip stops the axis at its deceleration; the reset waits for rest.
  REQUIRE(wait_until([&] { return c.read("axis.x.velocity") == 0 && c.read("axis.x.busy") == 0; }, 10s));
  // Each command's result is read once the control loop took it (status.command_count).
  const auto commands = c.read("status.command_count");
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") >= commands + 1; }, 5s));
  CHECK(c.read("axis.x.alarm") == 0);
  CHECK(result_of(c) == static_cast<int>(homing::CommandResult::accepted));
  REQUIRE(c.write("cmd.jog_minus.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") >= commands + 2; }, 5s));
  CHECK(result_of(c) == static_cast<int>(homing::CommandResult::refused_hard_limit));
  REQUIRE(c.write("cmd.jog_minus.x", 0) == 0);
  const double x = c.read_mm("sim.x.actual_position");
  REQUIRE(c.write("cmd.jog_plus.x", 1) == 0);
  const auto away = Clock::now() + 20s;
  while (Clock::now() < away && c.read("sim.x.sensor") == 1) std::this_thread::sleep_for(5ms);
  REQUIRE(c.write("cmd.jog_plus.x", 0) == 0);
  CHECK(c.read("sim.x.sensor") == 0);
  CHECK(c.read_mm("sim.x.actual_position") > x);
  CHECK(c.read("axis.x.alarm") == 0);
}

TEST_CASE("over Modbus an absolute axis in no sequence step takes its coordinate from its encoder") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  c.set("axis.a.mode", 5);
  c.set("axis.a.home_position", um(10));
  c.set("sim.a.absolute_offset", um(5));
  c.set("sim.a.actual_position", um(43));
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  const auto deadline = Clock::now() + 30s;
  while (Clock::now() < deadline && !settled(c)) std::this_thread::sleep_for(5ms);
  REQUIRE(state_of(c) == static_cast<int>(homing::MachineState::homed));
  CHECK(c.read("axis.a.position") == um(43 + 5 - 10));
}

TEST_CASE("over Modbus a push the back-off cannot release is refused at write time: exception 03, nothing written") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  c.set("axis.x.mode", 7);  // pushing, release edge
  const auto push = c.read("axis.x.push_distance");
  CHECK(c.write("axis.x.push_distance", um(c.read_mm("axis.x.max_backoff") + 1)) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.read("axis.x.push_distance") == push);
}

TEST_CASE("over Modbus an unsequenced axis whose home position lies outside its soft limits cannot be configured") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  c.set("axis.a.mode", 1);  // manual, in no sequence step
  c.set("axis.a.soft_limit_min", um(-10));
  c.set("axis.a.soft_limit_max", um(10));
  c.set("axis.a.home_position", um(5));
  c.set("axis.a.soft_limits_enable", 1);
  CHECK(c.write("axis.a.home_position", um(50)) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.read("axis.a.home_position") == um(5));
}
