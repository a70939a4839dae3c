// Home cam in mid-travel with limit-switch reversal (home_cam) and the
// end-of-travel limit switches as hard limits (docs/limit-switches.md).
#include <catch2/catch.hpp>

#include <cmath>

#include <fmt/format.h>

#include "homing/alarms.hpp"
#include "homing/settings_check.hpp"
#include "rig.hpp"

using namespace rig;

namespace {

// X on a home cam between limit switches (fit_home_cam), 0.05 mm hysteresis.
Rig cam_rig(double start_mm, double cam_min, double cam_max, CamEdge edge = CamEdge::behind) {
  Rig r;
  fit_home_cam(r, start_mm, cam_min, cam_max, edge);
  r.settings.axes[0].max_seek_travel_mm = 300;
  return r;
}

bool ran(Rig& r, Phase p, const std::function<void()>& go) {
  bool seen = false;
  r.on_period = [&](Rig& rig) { seen = seen || rig.axis(0).phase == p; };
  go();
  r.on_period = nullptr;
  return seen;
}

}  // namespace

SCENARIO("home cam ahead of the start: found without reversal, its behind edge is the reference", "[limits][home_cam]") {
  Rig r = cam_rig(50, 10, 20);
  r.step();
  bool homed = false;
  const bool reversed = ran(r, Phase::limit_reversal, [&] { homed = r.home_all(); });
  REQUIRE(homed);
  CHECK_FALSE(reversed);
  // Behind edge (facing away from negative): the top of the cam, left upward at 20.05, pull-off 1 above.
  CHECK(r.axis(0).position_mm == Approx(r.actual(0) - 21.05).margin(0.01));
}

SCENARIO("home cam behind the start: the search reverses at the limit switch and finds it", "[limits][home_cam]") {
  Rig r = cam_rig(50, 60, 70);
  r.step();
  bool homed = false;
  const bool reversed = ran(r, Phase::limit_reversal, [&] { homed = r.home_all(); });
  REQUIRE(homed);
  CHECK(reversed);
  // Never further past the limit switch than the stop from seek feedrate (plus a period).
  CHECK(r.actual(0) > -110);
  CHECK(r.axis(0).position_mm == Approx(r.actual(0) - 71.05).margin(0.01));
}

SCENARIO("home cam: the reference edge is the same whichever side the cam was found from", "[limits][home_cam]") {
  for (const CamEdge edge : {CamEdge::behind, CamEdge::ahead}) {
    Rig direct = cam_rig(50, 10, 20, edge);
    Rig reversed = cam_rig(-50, 10, 20, edge);
    direct.step();
    reversed.step();
    REQUIRE(direct.home_all());
    REQUIRE(reversed.home_all());
    // Machine coordinate of the same carriage place agrees within edge precision.
    CHECK(direct.axis(0).position_mm - direct.actual(0) ==
          Approx(reversed.axis(0).position_mm - reversed.actual(0)).margin(0.01));
    const double rest = edge == CamEdge::ahead ? 10 - 0.05 - 1 : 20 + 0.05 + 1;
    CHECK(direct.actual(0) == Approx(rest).margin(0.01));
  }
}

SCENARIO("home cam not between the limit switches: cam_not_found", "[limits][home_cam][alarms]") {
  Rig r = cam_rig(50, 500, 600);  // the cam lies beyond the positive stop
  r.step();
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::cam_not_found);
  CHECK(r.axis(0).alarm.phase == Phase::limit_reversal);
  // The figure is where the search met the other limit switch, and the text says so.
  CHECK(r.axis(0).alarm.value == Approx(r.axis(0).position_mm).margin(0.5));
  const std::string text = describe_alarm(0, r.axis(0).alarm, r.settings);
  INFO(text);
  CHECK(text.find(fmt::format("met the other at {:.3f} mm", r.axis(0).alarm.value)) != std::string::npos);
}

SCENARIO("both limit switches active at once: both_limits_active, nothing searched", "[limits][home_cam][alarms]") {
  Rig r = cam_rig(50, 10, 20);
  r.machine.axes[0].fault = sim::Fault::limits_stuck;
  r.step();
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::both_limits_active);
  CHECK(r.actual(0) == Approx(50).margin(1e-6));
}

SCENARIO("both limit switches active at rest: a jog either way or a move is refused as both active, nothing moves",
         "[limits][hard_limit]") {
  // Found by a technician: each jog was refused "only a jog away", which no direction is.
  Rig r = cam_rig(50, 10, 20);
  r.machine.axes[0].fault = sim::Fault::limits_stuck;
  r.step();
  REQUIRE(r.status().interlocks & interlock::limit_active);
  for (const int dir : {+1, -1}) {
    r.jog(0, dir);
    r.step();
    CHECK(r.status().last_command_result == CommandResult::refused_both_limits);
    r.run_for(0.2);
    r.release_jogs();
    r.step();
  }
  r.move(0, 0);
  CHECK(r.status().last_command_result == CommandResult::refused_both_limits);
  r.run_for(0.2);
  CHECK(r.actual(0) == Approx(50).margin(1e-9));
  CHECK_FALSE(r.status().alarm);
  CHECK_THAT(std::string(text_of(CommandResult::refused_both_limits)),
             Catch::Contains("limits_nc") && Catch::Contains("wiring"));
  // Wired right again: the jog runs.
  r.set_fault(0, sim::Fault::none);
  r.step();
  r.jog(0, -1);
  r.step();
  CHECK(r.status().last_command_result == CommandResult::accepted);
  r.run_for(0.2);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(r.actual(0) < 50);
}

SCENARIO("a gantry slave standing on its limit switch: a jog or move of the pair toward it is refused, one away runs",
         "[limits][hard_limit][gantry]") {
  // Found in review: only the jogged axis's own limit switches were looked
  // at, so the pair was started onto the slave's switch and tripped it.
  Rig r;
  r.settings.axes[1] = typical_axis();
  r.settings.axes[1].slave_of = 1;
  r.settings.axes[1].limits_fitted = true;
  r.settings.axes[1].limit_overtravel_mm = 10;
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  for (std::size_t a : {0u, 1u}) r.machine.axes[a].actual_position_mm = 103;
  r.machine.axes[1].limit_min_mm = -100;
  r.machine.axes[1].limit_max_mm = 100;
  r.machine.axes[1].hard_stop_max_mm = 110;
  r.step();
  REQUIRE(r.status().interlocks & interlock::limit_active);
  r.jog(0, +1);  // the master toward the slave's active switch
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_hard_limit);
  r.run_for(0.2);
  r.release_jogs();
  r.step();
  r.move(0, 105);
  CHECK(r.status().last_command_result == CommandResult::refused_hard_limit);
  r.run_for(0.2);
  CHECK(r.actual(0) == Approx(103).margin(1e-9));
  CHECK(r.actual(1) == Approx(103).margin(1e-9));
  CHECK_FALSE(r.status().alarm);
  r.jog(0, -1);  // away
  r.step();
  CHECK(r.status().last_command_result == CommandResult::accepted);
  r.run_until([&] { return r.actual(1) < 99; }, 30);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(r.actual(1) < 100);
  CHECK_FALSE(r.status().alarm);
}

SCENARIO("a limit switch met in a phase that must not reach one: limit_in_homing", "[limits][home_cam][alarms]") {
  // The cam right at the negative limit, its far edge the reference: the latch runs into the limit switch.
  Rig r = cam_rig(50, -95, -90, CamEdge::ahead);
  r.machine.axes[0].limit_min_mm = -93;
  r.step();
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::limit_in_homing);
  CHECK(r.axis(0).alarm.phase == Phase::cam_latch);
  CHECK_THAT(describe_alarm(0, r.axis(0).alarm, r.settings),
             Catch::StartsWith("X: negative limit switch met during cam_latch at ") &&
                 Catch::Contains("check that the home sensor or cam lies well inside the limit switches"));
}

SCENARIO("limit_in_homing met on the way back of return_to_start says so, not a homing phase",
         "[limits][alarms][failure_policy]") {
  // The text of the alarm as raised in phase return_to_start (campaign seed 7201552).
  Rig r;
  const Alarm a{AlarmCode::limit_in_homing, Phase::return_to_start, AxisField::none, 12.5, 2};
  const std::string text = describe_alarm(0, a, r.settings);
  INFO(text);
  CHECK_THAT(text, Catch::StartsWith("X: positive limit switch met at 12.500 mm while going back to where the cycle "
                                     "found it (failure policy return_to_start)") &&
                       Catch::Contains("that an axis sent back by return_to_start did not start next to one"));
}

SCENARIO("home_cam without limit switches is refused before anything moves", "[limits][home_cam][rules]") {
  Rig r = cam_rig(50, 10, 20);
  r.settings.axes[0].limits_fitted = false;
  const auto f = check_axis(r.settings, 0);
  REQUIRE(f);
  CHECK(f->rule == CheckRule::cam_needs_limits);
  r.settings.axes[0].limits_fitted = true;
  r.settings.axes[0].limit_overtravel_mm = 0.1;
  const auto g = check_axis(r.settings, 0);
  REQUIRE(g);
  CHECK(g->rule == CheckRule::limit_overtravel_too_short);
}

SCENARIO("a reset in the very period a limit switch trips does not clear that alarm", "[limits][hard_limit][alarms]") {
  // The operator presses reset (for an older alarm) as the carriage meets
  // the switch: the new alarm was never shown, so it stays (seed 2818140234:
  // the cycle ended stopped with no alarm at all).
  auto jog_rig = [] {
    Rig r = cam_rig(99, 10, 20);
    r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
    r.step();
    r.jog(0, +1);
    return r;
  };
  Rig probe = jog_rig();
  REQUIRE(probe.run_until([&] { return probe.status().alarm; }, 10));
  const std::uint64_t trip_period = probe.periods;

  Rig r = jog_rig();
  while (r.periods + 1 < trip_period) r.step();
  r.pending.reset_alarm = true;
  r.step();
  CHECK(r.status().last_command_result == CommandResult::accepted);
  CHECK(r.axis(0).alarm.code == AlarmCode::limit_switch);
  CHECK(r.status().alarm);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(r.actual(0) < 110);  // it stopped for the alarm the reset did not clear
  r.reset_alarm();  // once seen, a reset clears it
  CHECK_FALSE(r.status().alarm);
}

SCENARIO("a jog onto a limit switch stops with limit_switch, within its acceleration, and jogs away only",
         "[limits][hard_limit][alarms]") {
  Rig r = cam_rig(95, 10, 20);
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.step();
  CHECK_FALSE(r.status().interlocks & interlock::limit_active);
  r.jog(0, +1);
  r.run_until([&] { return r.status().alarm; }, 10);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(r.axis(0).alarm.code == AlarmCode::limit_switch);
  CHECK(r.actual(0) >= 100);
  CHECK(r.actual(0) < 110);  // stopped before the mechanical stop
  r.reset_alarm();
  CHECK_FALSE(r.status().alarm);
  // Standing on the switch: shown before any jog is refused for it.
  CHECK(r.status().interlocks & interlock::limit_active);
  r.jog(0, +1);  // further in: refused
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_hard_limit);
  r.release_jogs();
  r.step();
  r.jog(0, -1);  // away: allowed until the switch releases
  r.step();
  CHECK(r.status().last_command_result == CommandResult::accepted);
  r.run_until([&] { return r.actual(0) < 99; }, 20);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK_FALSE(r.status().alarm);
  CHECK_FALSE(r.status().interlocks & interlock::limit_active);
}

SCENARIO("an axis powered up on a limit switch jogs off it even where nothing may move before homing, only away",
         "[limits][hard_limit]") {
  // docs/limit-switches.md: a jog away from it is allowed also before homing,
  // with no alarm raised first (a technician found it refused_not_homed).
  Rig r = cam_rig(103, 10, 20);
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::none;
  r.step();
  REQUIRE(r.status().interlocks & interlock::limit_active);
  r.jog(0, +1);  // further in
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_hard_limit);
  r.release_jogs();
  r.step();
  r.jog(0, -1);  // away
  r.step();
  CHECK(r.status().last_command_result == CommandResult::accepted);
  r.run_until([&] { return r.actual(0) < 99; }, 60);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(r.actual(0) < 100);
  CHECK_FALSE(r.status().alarm);
  // Off the switch, the rule holds again.
  r.jog(0, -1);
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_not_homed);
  r.release_jogs();
}

SCENARIO("a homing cycle started on a tripped limit switch does not drive further onto it",
         "[limits][home_cam][alarms]") {
  // The latch of the first cycle runs into the negative limit switch
  // (limit_in_homing) and brakes past it, still on the cam. After the reset
  // the switch is still active and tripped; the next cycle, starting on the
  // cam, latches toward it again: it must stop there with limit_in_homing at
  // once, not latch on toward the mechanical stop (campaign seed 97).
  Rig r = cam_rig(50, -95, -90, CamEdge::ahead);
  r.machine.axes[0].limit_min_mm = -93;
  r.step();
  REQUIRE_FALSE(r.home_all());
  REQUIRE(r.axis(0).alarm.code == AlarmCode::limit_in_homing);
  REQUIRE(r.actual(0) < -93);
  r.reset_alarm();
  REQUIRE_FALSE(r.status().alarm);
  const double x0 = r.actual(0);
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::limit_in_homing);
  CHECK(r.axis(0).alarm.phase == Phase::cam_latch);
  // Within the stop from latch feedrate (1 mm/s at 500 mm/s²) and a period of travel.
  CHECK(x0 - r.actual(0) < 0.01);
}

SCENARIO("a homing phase never starts toward an active limit switch: limit_in_homing before it moves",
         "[limits][home_cam][alarms]") {
  // As a jog or a move toward an active limit switch is refused, a latch,
  // pull-off or final move that would start toward one raises limit_in_homing
  // without a period of motion: cycle after cycle started there, the carriage
  // would otherwise creep deeper past the switch (campaign seed 1602).
  Rig r = cam_rig(50, -95, -90, CamEdge::ahead);
  r.machine.axes[0].limit_min_mm = -93;
  r.step();
  REQUIRE_FALSE(r.home_all());
  REQUIRE(r.axis(0).alarm.code == AlarmCode::limit_in_homing);
  for (int cycle = 0; cycle < 3; ++cycle) {
    r.reset_alarm();
    REQUIRE_FALSE(r.status().alarm);
    const double x0 = r.actual(0);
    CHECK_FALSE(r.home_all());
    CHECK(r.axis(0).alarm.code == AlarmCode::limit_in_homing);
    CHECK(r.axis(0).alarm.phase == Phase::cam_latch);
    CHECK(std::abs(r.actual(0) - x0) <= 1e-9);
  }
}

SCENARIO("a move that comes to rest on a limit switch in the period it reaches it still raises limit_switch",
         "[limits][hard_limit][alarms]") {
  // The target 0.01 mm past the switch and a control period 10 ms late as the
  // carriage gets there: the move arrives within the period in which it
  // reaches the switch, so the next period reads the switch active with the
  // axis already at rest (campaign seed 13003772: 0.6 mm past the switch at
  // 900 mm/s). The trip must show all the same.
  Rig r = cam_rig(95, 10, 20);
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.next_dt = [&] { return r.sim().actual_position_mm(0) > 99 ? 0.01 : 0.001; };
  r.step();
  const double target = r.axis(0).position_mm + (100 - r.actual(0)) + 0.01;
  r.move(0, target);
  REQUIRE(r.status().last_command_result == CommandResult::accepted);
  r.run_until([&] { return !r.any_moving() && r.axis(0).phase != Phase::move; }, 10);
  r.run_for(0.01);
  REQUIRE(r.actual(0) >= 100);  // on the switch
  CHECK(r.axis(0).alarm.code == AlarmCode::limit_switch);
  CHECK_THAT(describe_alarm(0, r.axis(0).alarm, r.settings),
             Catch::Contains("X: positive limit switch tripped during move at"));
  // Tripped: further onto it is refused, away is allowed.
  r.reset_alarm();
  r.jog(0, +1);
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_hard_limit);
  r.release_jogs();
  r.step();
  r.jog(0, -1);
  r.step();
  CHECK(r.status().last_command_result == CommandResult::accepted);
  r.release_jogs();
}

SCENARIO("a limit switch tripped by a gantry slave following its master's jog names the jog, not the phase done",
         "[limits][alarms][gantry]") {
  // Found by a technician: "B: positive limit switch tripped during done".
  Rig r;
  const Alarm tripped{AlarmCode::limit_switch, Phase::done, AxisField::none, 297.951, 2};
  CHECK(describe_alarm(1, tripped, r.settings).rfind(
            "Y: positive limit switch tripped at 297.951 mm while the axis moved outside homing (a jog or move, its "
            "own or its gantry partner's)",
            0) == 0);
}
