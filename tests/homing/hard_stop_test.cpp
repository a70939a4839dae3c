// Hard-stop homing: no switch; the axis pushes into its mechanical stop at
// latch feedrate with reduced current until the drive reports a stall, and
// the stop is the reference. Bounded by max_seek_travel and stall_timeout_ms.
#include <catch2/catch.hpp>

#include <algorithm>

#include "homing/settings_check.hpp"
#include "rig.hpp"

using namespace rig;

namespace {

// X homes negative against its stop at -5 mm; it starts at 3 mm (8 mm away:
// 8 s at the latch feedrate of 60 mm/min), pull-off 1 mm, home position 0.
Rig hard_stop_rig() {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.mode = HomingMode::hard_stop;
  s.stall_timeout_ms = 20'000;
  r.machine.axes[0].actual_position_mm = 3;
  r.machine.axes[0].hard_stop_min_mm = -5;
  r.machine.axes[0].sensor_min_mm = 1;  // no switch is in the way: the cam lies beyond the stop
  r.machine.axes[0].sensor_max_mm = 0;
  return r;
}

}  // namespace

SCENARIO("hard-stop homing: the stop is the reference, the push runs at reduced current until the stall",
         "[modes][hard_stop]") {
  Rig r = hard_stop_rig();
  bool push_seen = false, push_after_stall_cleared = false;
  r.on_period = [&](Rig& rig) {
    if (rig.axis(0).phase == Phase::push_to_stop) push_seen = push_seen || rig.engine.outputs().axes[0].push_output;
    if (rig.axis(0).phase == Phase::pull_off && rig.engine.outputs().axes[0].push_output) push_after_stall_cleared = true;
  };
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK(r.saw(0, Phase::push_to_stop));
  CHECK(push_seen);
  CHECK_FALSE(push_after_stall_cleared);  // full current again for the pull-off
  CHECK(r.trace[0].min_actual == Approx(-5).margin(1e-9));  // it reached the stop and never passed it
  CHECK(r.actual(0) == Approx(-4).margin(1e-9));             // pull_off above the stop
  CHECK(r.axis(0).position_mm == Approx(0).margin(1e-9));
  CHECK(r.axis(0).homed);
}

SCENARIO("hard-stop homing: the stall detection's delay and spread move the lost steps, never the home",
         "[modes][hard_stop]") {
  std::vector<double> lost;
  for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
    Rig r = hard_stop_rig();
    r.machine.seed = seed;
    r.machine.axes[0].stall_detect_ms = 30;
    r.machine.axes[0].stall_spread_ms = 40;
    r.step();
    const double believed_start = r.axis(0).position_mm;
    REQUIRE(r.home_all());
    CHECK(r.actual(0) == Approx(-4).margin(1e-9));
    CHECK(r.axis(0).position_mm == Approx(0).margin(1e-9));
    // What the counter lost at the stop: the correction the cycle applied.
    lost.push_back(r.axis(0).home_correction_mm);
    (void)believed_start;
  }
  // Different detection times, different lost steps: the spread is real.
  CHECK(*std::max_element(lost.begin(), lost.end()) - *std::min_element(lost.begin(), lost.end()) > 1e-3);
}

SCENARIO("hard-stop homing: no stall within max_seek_travel is stop_not_found, and the push goes no further",
         "[modes][hard_stop][alarms]") {
  Rig r = hard_stop_rig();
  r.settings.axes[0].max_seek_travel_mm = 4;  // the stop lies 8 mm away
  r.clear_trace();
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::stop_not_found);
  CHECK(r.axis(0).alarm.phase == Phase::push_to_stop);
  CHECK(r.axis(0).alarm.value == Approx(4).margin(1e-6));
  CHECK(r.trace[0].min_actual >= 3 - 4 - 1e-9);
  CHECK_FALSE(r.axis(0).homed);
  const std::string text = describe_alarm(0, r.axis(0).alarm, r.settings);
  CHECK_THAT(text, Catch::Contains("no stall reported within 4.000 mm"));
  CHECK_THAT(text, Catch::Contains("stall output is wired"));
}

SCENARIO("hard-stop homing: a stall output that never turns on ends in stop_not_found within the travel bound",
         "[modes][hard_stop][alarms]") {
  Rig r = hard_stop_rig();
  r.machine.axes[0].fault = sim::Fault::stall_dead;
  r.settings.axes[0].max_seek_travel_mm = 12;
  r.step();
  const double motor_start = r.engine.outputs().axes[0].motor.position_mm;
  double furthest = 0;
  r.on_period = [&](Rig& rig) {
    furthest = std::max(furthest, std::abs(rig.engine.outputs().axes[0].motor.position_mm - motor_start));
  };
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::stop_not_found);
  // The motor was never driven further than the travel bound: 8 mm to the
  // stop, then 4 mm of lost steps against it.
  CHECK(furthest <= 12 + 1e-6);
  CHECK(r.actual(0) == Approx(-5).margin(1e-9));
}

SCENARIO("hard-stop homing: pushing longer than stall_timeout_ms is stall_timeout", "[modes][hard_stop][alarms]") {
  Rig r = hard_stop_rig();
  r.settings.axes[0].stall_timeout_ms = 2'000;  // 2 s at 1 mm/s: the stop is 8 mm away
  r.clear_trace();
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::stall_timeout);
  CHECK(r.axis(0).alarm.phase == Phase::push_to_stop);
  CHECK(r.axis(0).alarm.value == Approx(2.0).margin(0.0011));
  CHECK(r.trace[0].min_actual > -5 + 1);  // stopped well before the stop
  CHECK_THAT(describe_alarm(0, r.axis(0).alarm, r.settings), Catch::Contains("stall_timeout_ms 2000"));
}

SCENARIO("hard-stop homing: a stall input already on before the push is stall_at_start and nothing moves",
         "[modes][hard_stop][alarms]") {
  Rig r = hard_stop_rig();
  r.machine.axes[0].fault = sim::Fault::stall_stuck;
  r.clear_trace();
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::stall_at_start);
  CHECK(r.trace[0].path_mm == 0);
  CHECK_FALSE(r.engine.outputs().axes[0].push_output);
  WHEN("the drive is reset and the stall clears") {
    r.machine.axes[0].fault = sim::Fault::none;
    r.sim().set_axis_config(0, r.machine.axes[0]);
    r.reset_alarm();
    THEN("the axis homes") {
      REQUIRE(r.home_all());
      CHECK(r.actual(0) == Approx(-4).margin(1e-9));
    }
  }
}

TEST_CASE("hard-stop homing needs a time bound and has no sensor to share with a limit", "[modes][hard_stop][rules]") {
  Settings s;
  s.axes[0] = typical_axis();
  s.axes[0].mode = HomingMode::hard_stop;
  REQUIRE_FALSE(check_axis(s, 0));
  SECTION("a stall_timeout_ms of 0 is refused") {
    s.axes[0].stall_timeout_ms = 0;
    const auto f = check_axis(s, 0);
    REQUIRE(f);
    CHECK(f->field == AxisField::stall_timeout_ms);
    CHECK(f->rule == CheckRule::not_positive);
  }
  SECTION("shared_limit is refused: there is no home sensor") {
    s.axes[0].shared_limit = true;
    const auto f = check_axis(s, 0);
    REQUIRE(f);
    CHECK(f->rule == CheckRule::shared_limit_without_sensor);
    CHECK_THAT(describe_fault(*f, s), Catch::Contains("axis.x.shared_limit: mode hard_stop homes without a home sensor"));
  }
  SECTION("it can be neither a gantry master nor a slave") {
    s.axes[1] = typical_axis();
    s.axes[1].slave_of = 1;
    s.axes[1].max_misalignment_mm = 2;
    const auto master = check_axis(s, 1);
    REQUIRE(master);
    CHECK(master->rule == CheckRule::slave_invalid);
    s.axes[0].mode = HomingMode::switch_release;
    s.axes[1].mode = HomingMode::hard_stop;
    const auto slave = check_axis(s, 1);
    REQUIRE(slave);
    CHECK(slave->rule == CheckRule::slave_needs_sensor);
  }
}

SCENARIO("hard-stop homing with limit switches: the switch before the stop it pushes into is on its way, the other "
         "end still trips",
         "[modes][hard_stop][limits]") {
  Rig r = hard_stop_rig();
  AxisSettings& s = r.settings.axes[0];
  s.limits_fitted = true;
  s.limit_overtravel_mm = 1.4;
  s.pull_off_mm = 2;                      // the rest, 2 mm off the stop, is off the switch
  r.machine.axes[0].limit_min_mm = -3.5;  // 1.5 mm before the stop at -5
  r.machine.axes[0].limit_max_mm = 100;
  REQUIRE_FALSE(check_axis(r.settings, 0));
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK(r.trace[0].min_actual == Approx(-5).margin(1e-9));  // through the switch, into the stop
  CHECK(r.axis(0).position_mm == Approx(0).margin(1e-9));
  CHECK(r.axis(0).homed);
  CHECK(r.actual(0) == Approx(-3).margin(1e-9));
  CHECK_FALSE(r.axis(0).alarm);
  // Homed, a move onto the same switch is a hard limit again.
  r.settings.axes[0].soft_limits_enable = false;
  r.move(0, -1.5);  // 0.5 mm past the switch
  r.run_for(2);
  CHECK(r.axis(0).alarm.code == AlarmCode::limit_switch);
}
