// Hard-stop homing on the real homingd over Modbus/TCP (libmodbus): X set to
// mode hard_stop over the wire homes against the simulator's mechanical stop,
// by the drive's stall input or by the encoder's following error, and each of
// its alarms is raised by a simulated fault, shown with its code, and reset.
#include <catch2/catch.hpp>

#include <cstdlib>

#include "daemon.hpp"
#include "homing/alarms.hpp"
#include "homing/settings.hpp"
#include "homing/settings_check.hpp"
#include "homing/sim/config.hpp"

using namespace e2e;
using namespace std::chrono_literals;

namespace {

bool cycle_over(Client& c) { return c.read("status.homing") == 0 && c.read("axis.x.velocity") == 0; }

// X alone: no cam anywhere (max below min), the carriage at 3 mm, its stop at -5 mm.
void hard_stop_machine(Client& c) {
  c.set("sim.x.sensor_min", 1'000'000);
  c.set("sim.x.sensor_max", 0);
  c.set("sim.x.hard_stop_min", -5'000);
  c.set("sim.x.actual_position", 3'000);
  c.set("axis.x.mode", static_cast<std::int64_t>(homing::HomingMode::hard_stop));
}

void home_x(Client& c) {
  REQUIRE(c.write("cmd.home.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.homing") == 1 || c.read("status.alarm") == 1; }, 5s, 5ms));
  REQUIRE(wait_until([&] { return cycle_over(c); }, 20s, 10ms));
}

std::int64_t code(homing::AlarmCode a) { return static_cast<std::int64_t>(a); }

}  // namespace

TEST_CASE("hard-stop homing over Modbus homes against the stop, and each of its alarms is raised and reset") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  hard_stop_machine(c);
  REQUIRE(c.read("axis.x.mode") == static_cast<std::int64_t>(homing::HomingMode::hard_stop));

  home_x(c);
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("axis.x.homed") == 1);
  CHECK(c.read("axis.x.position") == 0);              // home_position
  CHECK(c.read("sim.x.actual_position") == -4'000);   // pull_off (1 mm) above the stop
  CHECK(c.read("axis.x.phase") == static_cast<std::int64_t>(homing::Phase::done));

  SECTION("a stall output that never turns on: stop_not_found within max_seek_travel") {
    c.set("axis.x.max_seek_travel", 3'000);
    c.set("sim.x.fault", static_cast<std::int64_t>(homing::sim::Fault::stall_dead));
    home_x(c);
    CHECK(c.read("status.alarm") == 1);
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::stop_not_found));
    CHECK(c.read("axis.x.alarm_phase") == static_cast<std::int64_t>(homing::Phase::push_to_stop));
    CHECK(c.read("sim.x.actual_position") == -5'000);  // at the stop, 2 mm of steps lost against it
  }
  SECTION("no stall within stall_timeout_ms: stall_timeout") {
    c.set("sim.x.actual_position", 3'000);
    c.set("axis.x.stall_timeout_ms", 500);  // 0.5 s at 100 mm/min: 0.83 mm of the 8 mm
    home_x(c);
    CHECK(c.read("status.alarm") == 1);
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::stall_timeout));
    CHECK(c.read("sim.x.actual_position") > 1'000);
  }
  SECTION("a stall output on before the push: stall_at_start, and nothing moves") {
    c.set("sim.x.fault", static_cast<std::int64_t>(homing::sim::Fault::stall_stuck));
    const auto before = c.read("sim.x.actual_position");
    home_x(c);
    CHECK(c.read("status.alarm") == 1);
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::stall_at_start));
    CHECK(c.read("sim.x.actual_position") == before);
  }
  // Reset once the cause is gone, then home again.
  c.set("sim.x.fault", 0);
  c.set("axis.x.stall_timeout_ms", 30'000);
  c.set("axis.x.max_seek_travel", 500'000);
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 0; }, 2s));
  CHECK(c.read("axis.x.alarm") == 0);
  home_x(c);
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("axis.x.homed") == 1);
  CHECK(c.read("sim.x.actual_position") == -4'000);
}

TEST_CASE("hard-stop homing by following error over Modbus: the encoder tells the stop, the stall input is not read") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  hard_stop_machine(c);
  // A limit within the encoder's noise is refused at write time, naming the rule; nothing is written.
  c.set("axis.x.stall_detect", static_cast<std::int64_t>(homing::StallDetect::following_error));
  CHECK(c.write("axis.x.max_following_error", 10) == 3);  // 0.01 mm
  CHECK(c.read("status.last_refusal_reason") ==
        registers::kRuleReasonBase + static_cast<std::int64_t>(homing::CheckRule::following_error_in_noise));
  CHECK(c.read("axis.x.max_following_error") == 200);  // the default, 0.2 mm
  c.set("axis.x.max_following_error", 300);
  // A dead stall output: only the encoder can tell the stop.
  c.set("sim.x.fault", static_cast<std::int64_t>(homing::sim::Fault::stall_dead));

  home_x(c);
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("axis.x.homed") == 1);
  CHECK(c.read("axis.x.position") == 0);             // home_position
  CHECK(c.read("sim.x.actual_position") == -4'000);  // pull_off (1 mm) above the stop
  // Homed again from there: the home correction is the steps lost against the
  // stop, pushed on until the carriage lagged by more than the 0.3 mm, and
  // hardly further (a late wall period runs as several 1 ms engine periods:
  // one period's travel and the braking from latch feedrate, some 5 um).
  home_x(c);
  CHECK(c.read("axis.x.homed") == 1);
  CHECK(c.read("sim.x.actual_position") == -4'000);
  const auto lost_um = std::abs(c.read("axis.x.home_correction"));
  CHECK(lost_um >= 300);
  CHECK(lost_um <= 310);

  SECTION("a limit too large to reach within max_seek_travel: stop_not_found, the push no further") {
    c.set("sim.x.actual_position", 3'000);       // 8 mm from the stop
    c.set("axis.x.max_seek_travel", 9'500);      // 1.5 mm of push left against it
    c.set("axis.x.max_following_error", 2'000);  // 2 mm: never reached
    home_x(c);
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::stop_not_found));
    CHECK(c.read("axis.x.alarm_phase") == static_cast<std::int64_t>(homing::Phase::push_to_stop));
    CHECK(c.read("axis.x.alarm_value") == 9'500);
    CHECK(c.read("sim.x.actual_position") == -5'000);
  }
  SECTION("an encoder that counts the wrong way: encoder_reversed, nothing homed") {
    c.set("sim.x.fault", static_cast<std::int64_t>(homing::sim::Fault::encoder_reversed));
    home_x(c);
    CHECK(c.read("axis.x.alarm") == code(homing::AlarmCode::encoder_reversed));
    CHECK(c.read("axis.x.homed") == 0);
    // From -4 mm it moved toward the stop by less than the 0.3 mm limit, and stopped there.
    const auto x = c.read("sim.x.actual_position");
    CHECK(x < -4'000);
    CHECK(x > -4'300);
    c.set("sim.x.fault", 0);
    REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("status.alarm") == 0; }, 2s));
    home_x(c);
    CHECK(c.read("axis.x.homed") == 1);
    CHECK(c.read("sim.x.actual_position") == -4'000);
  }
}
