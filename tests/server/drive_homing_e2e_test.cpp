// Drive-performed homing over Modbus/TCP on the real homingd with its
// simulator unit: X set to axis.x.mode = drive homes end to end (the drive
// moves the carriage to its own home, the module assigns home_position
// there), and each of the method's alarms is caused through sim.x.fault,
// read with its phase, and reset.
#include <catch2/catch.hpp>

#include "daemon.hpp"
#include "homing/alarms.hpp"
#include "homing/modes.hpp"
#include "homing/phases.hpp"
#include "homing/settings_check.hpp"
#include "homing/sim/config.hpp"
#include "homing/status.hpp"

using namespace e2e;
using homing::AlarmCode;
using homing::Phase;

namespace {

template <class E>
std::int64_t v(E e) {
  return static_cast<std::int64_t>(e);
}

// X homed by its drive alone: Y and Z disabled, X in step 1.
void drive_machine(Client& c, double timeout_s) {
  c.set("axis.y.mode", v(homing::HomingMode::disabled));
  c.set("axis.z.mode", v(homing::HomingMode::disabled));
  c.set("sequence.step1", 0b001);
  c.set("sequence.step2", 0);
  c.set("axis.x.drive_home_timeout_s", static_cast<std::int64_t>(timeout_s));
  c.set("axis.x.mode", v(homing::HomingMode::drive));
  c.set("axis.x.home_position", um(7.0));
  c.set("sim.x.actual_position", um(60.0));
  c.set("sim.x.drive_home_position", um(-2.5));
  c.set("sim.x.drive_speed", 1200);
  c.set("sim.x.drive_answer_ms", 200);
}

bool wait_alarm(Client& c, std::chrono::seconds within) {
  return wait_until([&] { return c.read("status.alarm") != 0; }, within);
}

void reset_clears(Client& c) {
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 0; }, 2s));
  CHECK(c.read("status.last_command_result") == v(homing::CommandResult::accepted));
  CHECK(c.read("axis.x.alarm") == 0);
}

}  // namespace

TEST_CASE("over Modbus: the drive homes X itself and the module assigns home_position where it reports done") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  drive_machine(c, 30);
  CHECK(c.read("axis.x.drive_home_timeout_s") == 30);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  bool saw_drive_homing = false;
  REQUIRE(wait_until(
      [&] {
        saw_drive_homing = saw_drive_homing || c.read("axis.x.phase") == v(Phase::drive_homing);
        return c.read("status.state") == v(homing::MachineState::homed) || c.read("status.alarm") != 0;
      },
      20s));
  CHECK(saw_drive_homing);
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("axis.x.homed") == 1);
  CHECK(c.read_mm("sim.x.actual_position") == Approx(-2.5).margin(0.001));
  CHECK(c.read("axis.x.position") == um(7.0));
  // It then moves in that coordinate.
  c.set("axis.x.target", um(17.0));
  REQUIRE(c.write("cmd.move.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("axis.x.position") == um(17.0) && c.read("axis.x.busy") == 0; }, 10s));
  CHECK(c.read_mm("sim.x.actual_position") == Approx(7.5).margin(0.001));
}

TEST_CASE("over Modbus: each drive-homing alarm is raised with its code and phase, and reset") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());

  SECTION("drive_no_answer: the drive never reports done") {
    drive_machine(c, 2);
    c.set("sim.x.fault", v(homing::sim::Fault::drive_never_answers));
    REQUIRE(c.write("cmd.home_all", 1) == 0);
    REQUIRE(wait_alarm(c, 10s));
    CHECK(c.read("axis.x.alarm") == v(AlarmCode::drive_no_answer));
    CHECK(c.read("axis.x.alarm_phase") == v(Phase::drive_homing));
    CHECK(c.read("axis.x.homed") == 0);
    c.set("sim.x.fault", v(homing::sim::Fault::none));
    reset_clears(c);
  }
  SECTION("drive_answered_at_once: the drive reports done without homing") {
    drive_machine(c, 30);
    c.set("sim.x.fault", v(homing::sim::Fault::drive_answers_at_once));
    REQUIRE(c.write("cmd.home_all", 1) == 0);
    REQUIRE(wait_alarm(c, 10s));
    CHECK(c.read("axis.x.alarm") == v(AlarmCode::drive_answered_at_once));
    CHECK(c.read("axis.x.alarm_phase") == v(Phase::drive_homing));
    CHECK(c.read_mm("sim.x.actual_position") == Approx(60.0).margin(0.001));
    c.set("sim.x.fault", v(homing::sim::Fault::none));
    reset_clears(c);
  }
  SECTION("drive_reference_lost: done drops while X is homed") {
    drive_machine(c, 30);
    REQUIRE(c.write("cmd.home_all", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("status.state") == v(homing::MachineState::homed); }, 20s));
    c.set("sim.x.fault", v(homing::sim::Fault::drive_done_lost));
    REQUIRE(wait_alarm(c, 5s));
    CHECK(c.read("axis.x.alarm") == v(AlarmCode::drive_reference_lost));
    CHECK(c.read("axis.x.homed") == 0);
    c.set("sim.x.fault", v(homing::sim::Fault::none));
    reset_clears(c);
    CHECK(c.read("axis.x.homed") == 0);
    // Homed again by the repaired drive.
    REQUIRE(c.write("cmd.home_all", 1) == 0);
    CHECK(wait_until([&] { return c.read("status.state") == v(homing::MachineState::homed); }, 20s));
  }
  SECTION("drive_fault: the drive's alarm input during its homing, with the phase") {
    drive_machine(c, 30);
    // The drive is on its home already and takes 5 s to answer: its carriage
    // rests, so the simulator takes the fault (a moving carriage refuses writes).
    c.set("sim.x.drive_home_position", um(60.0));
    c.set("sim.x.drive_answer_ms", 5000);
    REQUIRE(c.write("cmd.home_all", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("axis.x.phase") == v(Phase::drive_homing); }, 5s));
    c.set("sim.x.fault", v(homing::sim::Fault::drive_fault));
    REQUIRE(wait_alarm(c, 5s));
    CHECK(c.read("axis.x.alarm") == v(AlarmCode::drive_fault));
    CHECK(c.read("axis.x.alarm_phase") == v(Phase::drive_homing));
    // Reset is refused while the drive still faults, taken once it is cleared.
    const auto commands = c.read("status.command_count");
    REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("status.command_count") != commands; }, 2s));
    CHECK(c.read("status.last_command_result") == v(homing::CommandResult::refused_cause_present));
    c.set("sim.x.fault", v(homing::sim::Fault::none));
    reset_clears(c);
  }
}

TEST_CASE("over Modbus: drive mode without a time limit is refused at write time, naming the setting") {
  Daemon d;
  Client c = Client::tcp(d.port());
  c.set("axis.x.drive_home_timeout_s", 0);
  CHECK(c.write("axis.x.mode", v(homing::HomingMode::drive)) != 0);
  CHECK(c.read("axis.x.mode") == v(homing::HomingMode::switch_release));
  CHECK(c.read("status.last_refusal_reason") == registers::kRuleReasonBase + v(homing::CheckRule::missing_time_limit));
}
