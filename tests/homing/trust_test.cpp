// Position trust across restarts (homing/trust.hpp): an axis that came to
// rest under control is offered a reference check after a restart; the check
// homes it when its switch edge lies where its stored position says, and is
// refused with the figure when the carriage was moved meanwhile. A restart is
// a new engine on the same simulated machine (the carriages stay where they
// were), given the last stops the runtime kept.
#include <catch2/catch.hpp>

#include "homing/last_stop.hpp"
#include "rig.hpp"

using namespace rig;

namespace {
constexpr std::size_t X = 0, Y = 1;

// The stops the runtime records at a clean shutdown of this rig.
LastStops shut_down(Rig& r) { return last_stops_at_shutdown(r.settings, r.status(), r.engine.outputs()); }

// A new engine on the same machine and settings, its carriages where they
// were, given `stops` in its first period.
Rig restart(Rig& before, const std::optional<LastStops>& stops) {
  Rig after;
  after.settings = before.settings;
  after.machine = before.machine;
  for (std::size_t a = 0; a < kAxisCount; ++a) after.machine.axes[a].actual_position_mm = before.actual(a);
  after.restore = stops;
  after.step();
  return after;
}

// Runs cmd.refcheck of these axes to its end; the command's result.
CommandResult refcheck(Rig& r, AxisMask axes) {
  r.pending.refcheck_axes = axes;
  r.step();
  const CommandResult result = r.status().last_command_result;
  r.run_until([&] { return !r.status().homing; }, 60);
  r.run_until([&] { return !r.any_moving(); }, 5);
  return result;
}

// Homed, then shut down cleanly: what the restarted engine is given.
struct CleanStop {
  Rig before;
  LastStops stops{};
  double offset_mm = 0;  // machine coordinate less carriage position, as the cycle homed it
};
void home_and_stop(CleanStop& c) {
  REQUIRE(c.before.home_all());
  c.stops = shut_down(c.before);
  c.offset_mm = c.before.axis(X).position_mm - c.before.actual(X);
}

// The check homed X within its tolerance, with the coordinate the cycle gave
// this carriage, and raised nothing.
void homed_by_the_check(Rig& r, const CleanStop& c, double tolerance_mm) {
  CHECK(r.axis(X).homed);
  CHECK(r.axis(X).trust == Trust::reference_checked);
  CHECK(std::abs(r.axis(X).refcheck_error_mm) <= tolerance_mm);
  CHECK_FALSE(r.status().alarm);
  CHECK(r.axis(X).position_mm - r.actual(X) == Approx(c.offset_mm).margin(tolerance_mm));
}

// X homes by re-approaching a home switch that doubles as its limit, whose
// hysteresis is this (soft limits from -2 mm).
AxisSettings& shared_limit_reapproach(CleanStop& c, double hysteresis_mm) {
  AxisSettings& s = c.before.settings.axes[X];
  s.mode = HomingMode::switch_reapproach;
  s.shared_limit = true;
  s.soft_limit_min_mm = -2;
  c.before.machine.axes[X].hysteresis_mm = hysteresis_mm;
  return s;
}

// X homes on the behind edge (the top) of a cam over [10, 20] in mid-travel,
// between limit switches, from carriage 50.
AxisSettings& home_cam_between_limits(CleanStop& c) {
  fit_home_cam(c.before, 50, 10, 20, CamEdge::behind);
  return c.before.settings.axes[X];
}

}  // namespace

SCENARIO("a restart after a clean stop offers a reference check, which homes the carriage left where it was without a full cycle",
         "[trust]") {
  CleanStop c;
  home_and_stop(c);
  REQUIRE(c.stops[X].clean);
  REQUIRE(c.before.axis(X).trust == Trust::homed_this_power_on);

  Rig r = restart(c.before, c.stops);
  THEN("it is not homed, trusts its last stop, and shows the stored position") {
    CHECK_FALSE(r.axis(X).homed);
    CHECK(r.axis(X).trust == Trust::last_stop_clean);
    CHECK(r.axis(X).position_mm == Approx(c.stops[X].position_mm));
  }
  WHEN("the reference check runs") {
    const double start = r.actual(X);
    r.clear_trace();
    CHECK(refcheck(r, axis_bit(X)) == CommandResult::accepted);
    THEN("the axis is homed by the check, within the tolerance, at latch speed, and back where it started") {
      CHECK(r.axis(X).homed);
      CHECK(r.axis(X).trust == Trust::reference_checked);
      CHECK(std::abs(r.axis(X).refcheck_error_mm) <= r.settings.axes[X].refcheck_tolerance_mm);
      CHECK(r.saw(X, Phase::reference_check));
      CHECK_FALSE(r.saw(X, Phase::seek));
      CHECK_FALSE(r.saw(X, Phase::pull_off));
      CHECK(r.status().homing_cycles == 0);  // a check is no homing cycle
      CHECK_FALSE(r.status().alarm);
      // To the edge (pull-off away) and back: a few mm, not the 100 mm of a seek.
      CHECK(r.trace[X].path_mm < 4 * r.settings.axes[X].pull_off_mm);
      CHECK(r.actual(X) == Approx(start).margin(1e-9));
      CHECK(r.axis(X).phase == Phase::done);
      // The coordinate is the one the full cycle gave this carriage, within the tolerance.
      CHECK(r.axis(X).position_mm - r.actual(X) == Approx(c.offset_mm).margin(r.settings.axes[X].refcheck_tolerance_mm));
    }
    THEN("a second check is refused: the axis is homed already") {
      CHECK(refcheck(r, axis_bit(X)) == CommandResult::refused_no_clean_stop);
    }
  }
}

SCENARIO("a restart after a clean stop, the carriage moved by hand: the reference check is refused with the figure",
         "[trust]") {
  const double moved = GENERATE(0.5, -1.6, 3.0);  // away from the switch, onto it, further away
  CAPTURE(moved);
  CleanStop c;
  home_and_stop(c);
  Rig r = restart(c.before, c.stops);
  const double stored_at = r.actual(X);
  REQUIRE(r.sim().place(X, stored_at + moved));
  r.step();
  REQUIRE(r.axis(X).trust == Trust::last_stop_clean);

  CHECK(refcheck(r, axis_bit(X)) == CommandResult::accepted);  // it ran
  THEN("the edge is found as far off as the carriage was moved, the axis stays unhomed and back where it stood") {
    CHECK_FALSE(r.axis(X).homed);
    CHECK(r.axis(X).trust == Trust::unknown);
    // Moved by +d, the edge is met d later than expected: the figure is -d.
    CHECK(r.axis(X).refcheck_error_mm == Approx(-moved).margin(0.01));
    CHECK(r.axis(X).phase == Phase::idle);
    CHECK_FALSE(r.status().alarm);
    CHECK(r.actual(X) == Approx(stored_at + moved).margin(1e-9));
  }
  THEN("the check is not offered again, and a full cycle homes the axis") {
    CHECK(refcheck(r, axis_bit(X)) == CommandResult::refused_no_clean_stop);
    REQUIRE(r.home_all());
    CHECK(r.axis(X).trust == Trust::homed_this_power_on);
    CHECK(r.axis(X).position_mm - r.actual(X) == Approx(c.offset_mm).margin(0.01));
  }
}

SCENARIO("a restart after an unclean stop offers no reference check", "[trust]") {
  CleanStop c;
  home_and_stop(c);
  SECTION("an alarm latched when the module stopped") {
    c.before.sim().set_estop(true);
    c.before.step();
    REQUIRE(c.before.status().alarm);
    c.stops = shut_down(c.before);
    CHECK_FALSE(c.stops[X].clean);
  }
  SECTION("stopped while homing (SIGTERM aborts the cycle: an alarm)") {
    c.before.pending.home_all = true;
    c.before.run_until([&] { return c.before.any_moving(); }, 1);
    c.before.pending.abort = true;
    c.before.run_until([&] { return !c.before.any_moving(); }, 5);
    c.stops = shut_down(c.before);
    CHECK_FALSE(c.stops[X].clean);
  }
  SECTION("not homed when the module stopped") {
    c.before.pending.unhome_axes = axis_bit(X);
    c.before.step();
    c.stops = shut_down(c.before);
    CHECK_FALSE(c.stops[X].clean);
  }
  SECTION("killed: nothing clean was recorded (the runtime wipes the mark at start)") {
    for (LastStop& s : c.stops) s.clean = false;
  }
  Rig r = restart(c.before, c.stops);
  r.clear_trace();
  CHECK(r.axis(X).trust == Trust::unknown);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::refused_no_clean_stop);
  CHECK(r.trace[X].path_mm == 0);
}

SCENARIO("a restart without any record of the last stops offers no reference check", "[trust]") {
  CleanStop c;
  home_and_stop(c);
  Rig r = restart(c.before, std::nullopt);
  CHECK(r.axis(X).trust == Trust::unknown);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::refused_no_clean_stop);
}

SCENARIO("a home setting changed since the last stop withdraws the reference check", "[trust]") {
  CleanStop c;
  home_and_stop(c);
  Rig r = restart(c.before, c.stops);
  REQUIRE(r.axis(X).trust == Trust::last_stop_clean);
  r.settings.axes[X].pull_off_mm = 2;
  r.step();
  CHECK(r.axis(X).trust == Trust::unknown);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::refused_no_clean_stop);
}

SCENARIO("a jog before the reference check keeps the stored position: steps are counted from it", "[trust]") {
  CleanStop c;
  home_and_stop(c);
  Rig r = restart(c.before, c.stops);
  r.jog(X, +1);
  r.run_for(0.5);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  REQUIRE(r.axis(X).trust == Trust::last_stop_clean);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::accepted);
  CHECK(r.axis(X).trust == Trust::reference_checked);
}

SCENARIO("an alarm before the reference check withdraws it (global.alarm_clears_homed)", "[trust]") {
  CleanStop c;
  home_and_stop(c);
  Rig r = restart(c.before, c.stops);
  r.sim().set_estop(true);
  r.step();
  r.sim().set_estop(false);
  r.reset_alarm();
  CHECK(r.axis(X).trust == Trust::unknown);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::refused_no_clean_stop);
}

SCENARIO("a reference check is refused for a method without a switch edge and for a gantry pair, and nothing moves",
         "[trust]") {
  CleanStop c;
  CommandResult expected = CommandResult::accepted;
  SECTION("manual: no switch edge") {
    c.before.settings.axes[X].mode = HomingMode::manual;
    expected = CommandResult::refused_no_switch_edge;
  }
  SECTION("hard stop: no switch edge") {
    c.before.settings.axes[X].mode = HomingMode::hard_stop;
    expected = CommandResult::refused_no_switch_edge;
  }
  SECTION("a software-slaved gantry") {
    c.before.settings.axes[Y] = typical_axis();
    c.before.settings.axes[Y].slave_of = X + 1;
    c.before.settings.axes[Y].max_misalignment_mm = 2;
    c.before.machine.axes[Y].actual_position_mm = 100;
    expected = CommandResult::refused_gantry_pair;
  }
  home_and_stop(c);
  REQUIRE(c.stops[X].clean);
  Rig r = restart(c.before, c.stops);
  CHECK(r.axis(X).trust == Trust::last_stop_clean);
  r.clear_trace();
  CHECK(refcheck(r, axis_bit(X)) == expected);
  CHECK(r.trace[X].path_mm == 0);
  CHECK(r.axis(X).trust == Trust::last_stop_clean);  // still offered: nothing was tried
}

SCENARIO("an abort during the reference check stops it with the aborted alarm", "[trust]") {
  CleanStop c;
  home_and_stop(c);
  Rig r = restart(c.before, c.stops);
  r.pending.refcheck_axes = axis_bit(X);
  r.step();
  REQUIRE(r.run_until([&] { return r.any_moving(); }, 1));
  CHECK(r.status().state == MachineState::homing);
  CHECK(r.axis(X).phase == Phase::reference_check);
  r.pending.abort = true;
  r.step();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(r.axis(X).alarm.code == AlarmCode::aborted);
  CHECK(r.axis(X).alarm.phase == Phase::reference_check);
  CHECK_FALSE(r.axis(X).homed);
}

SCENARIO("a home cam axis whose cam edge changed since the last stop is offered no reference check",
         "[trust][home_cam][home_frame]") {
  // Found by a technician: the edge was no part of the home frame, so the
  // check was offered and then refused as a carriage moved by the cam's width.
  CleanStop c;
  home_cam_between_limits(c);
  home_and_stop(c);
  Rig r = restart(c.before, c.stops);
  REQUIRE(r.axis(X).trust == Trust::last_stop_clean);
  r.settings.axes[X].cam_edge = CamEdge::ahead;
  r.step();
  CHECK(r.axis(X).trust == Trust::unknown);
  const double start = r.actual(X);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::refused_no_clean_stop);
  CHECK(r.actual(X) == start);
}

SCENARIO("a home cam axis restarted with its cam edge unchanged is offered the reference check and homed by it",
         "[trust][home_cam][home_frame]") {
  CleanStop c;
  home_cam_between_limits(c);
  home_and_stop(c);
  Rig r = restart(c.before, c.stops);
  CHECK(r.axis(X).trust == Trust::last_stop_clean);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::accepted);
  CHECK(r.axis(X).homed);
}

SCENARIO("a home cam axis left on the cam's far side is checked across the cam and accepted where it stands",
         "[trust][home_cam]") {
  // Campaign seed 187000328: a home cam lies in mid-travel, so a homed axis
  // may rest beyond it (a final move or a jog across it); the check took
  // that for a carriage moved past its edge and refused it with the cam's width.
  CleanStop c;
  const AxisSettings& s = home_cam_between_limits(c);  // the top of the cam, left upward, is the reference
  const bool on_cam = GENERATE(false, true);
  CAPTURE(on_cam);
  REQUIRE(c.before.home_all());
  // Across the cam (to carriage -4), or onto it, 6 mm from the reference edge.
  c.before.move(X, c.before.axis(X).position_mm - (on_cam ? 7 : 25));
  c.before.run_until([&] { return !c.before.any_moving() && c.before.axis(X).phase == Phase::idle; }, 30);
  REQUIRE(c.before.sim().sensor_active(X) == on_cam);
  c.stops = shut_down(c.before);
  c.offset_mm = c.before.axis(X).position_mm - c.before.actual(X);
  REQUIRE(c.stops[X].clean);

  Rig r = restart(c.before, c.stops);
  const double start = r.actual(X);
  REQUIRE(r.axis(X).trust == Trust::last_stop_clean);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::accepted);
  homed_by_the_check(r, c, s.refcheck_tolerance_mm);
  // Off the cam it goes back where it stood; from on it, it ends where a cycle ends.
  if (!on_cam) CHECK(r.actual(X) == Approx(start).margin(1e-9));
  else CHECK(r.axis(X).position_mm == Approx(s.home_position_mm).margin(s.refcheck_tolerance_mm));
}

SCENARIO("a switch axis left past its switch flag by a final move is checked back across the flag and accepted where "
         "it stands",
         "[trust]") {
  // Campaign seed 993609: a home switch that is a short flag under a
  // proximity sensor lies in mid-travel like a home cam; a final move past
  // it left the axis off the flag beyond its edge, and the check took that
  // for a carriage moved and refused it at once.
  CleanStop c;
  AxisSettings& s = c.before.settings.axes[X];
  s.mode = GENERATE(HomingMode::switch_release, HomingMode::switch_reapproach);
  CAPTURE(s.mode);
  s.soft_limit_min_mm = -100;
  sim::AxisConfig& m = c.before.machine.axes[X];
  m.sensor_min_mm = -3;  // a 3 mm flag, travel on both sides of it
  m.sensor_max_mm = 0;
  m.hard_stop_min_mm = -200;
  REQUIRE(c.before.home_all());
  // Past the flag, toward the seek's side, off it.
  c.before.move(X, c.before.axis(X).position_mm - 8);
  c.before.run_until([&] { return !c.before.any_moving() && c.before.axis(X).phase == Phase::idle; }, 30);
  REQUIRE_FALSE(c.before.sim().sensor_active(X));
  REQUIRE(c.before.actual(X) < m.sensor_min_mm);
  c.stops = shut_down(c.before);
  c.offset_mm = c.before.axis(X).position_mm - c.before.actual(X);
  REQUIRE(c.stops[X].clean);

  Rig r = restart(c.before, c.stops);
  const double start = r.actual(X);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::accepted);
  homed_by_the_check(r, c, s.refcheck_tolerance_mm);
  CHECK(r.actual(X) == Approx(start).margin(1e-9));  // back where it stood
}

SCENARIO("an axis left deeper on its switch than max_backoff is checked off it and accepted where it stands",
         "[trust]") {
  // Campaign seed 187105905: a final move left the axis on its switch; the
  // check backed off no further than max_backoff from where it stood, never
  // met the release edge and refused an axis that had not moved.
  CleanStop c;
  c.before.settings.axes[X].soft_limit_min_mm = -100;
  c.before.machine.axes[X].hard_stop_min_mm = -50;  // room on the switch
  home_and_stop(c);
  // 15 mm onto the switch (its edge 1 mm below the home position), past max_backoff (10 mm).
  c.before.move(X, -16);
  c.before.run_until([&] { return !c.before.any_moving(); }, 30);
  c.before.step();
  REQUIRE(c.before.actual(X) == Approx(-14.95).margin(1e-6));
  REQUIRE(c.before.sim().sensor_active(X));
  c.stops = shut_down(c.before);
  REQUIRE(c.stops[X].clean);
  Rig r = restart(c.before, c.stops);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::accepted);
  CHECK(r.axis(X).homed);
  CHECK(r.axis(X).trust == Trust::reference_checked);
  CHECK(std::abs(r.axis(X).refcheck_error_mm) <= r.settings.axes[X].refcheck_tolerance_mm);
  // Homed where a cycle ends: pull_off off the edge, with the coordinate the cycle gave it.
  CHECK(r.axis(X).position_mm == Approx(0).margin(0.01));
  CHECK(r.axis(X).position_mm - r.actual(X) == Approx(c.offset_mm).margin(r.settings.axes[X].refcheck_tolerance_mm));
}

SCENARIO("a release method whose switch's hysteresis exceeds the check's search past the edge is accepted where it stopped",
         "[trust]") {
  // Campaign seeds 187201697, 187209246: the approach looked for the trigger
  // no further than tolerance + max_stop_distance past the release edge it
  // checks, but the trigger lies the switch's hysteresis beyond it: an
  // unmoved axis was refused with the search's end as its figure.
  CleanStop c;
  c.before.settings.axes[X].max_stop_distance_mm = 0.45;  // the seek needs 0.4
  c.before.machine.axes[X].hysteresis_mm = 0.6;           // beyond 0.1 + 0.45
  home_and_stop(c);
  REQUIRE(c.stops[X].clean);
  Rig r = restart(c.before, c.stops);
  const double start = r.actual(X);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::accepted);
  CHECK(r.axis(X).trust == Trust::reference_checked);
  CHECK(std::abs(r.axis(X).refcheck_error_mm) <= r.settings.axes[X].refcheck_tolerance_mm);
  CHECK(r.actual(X) == Approx(start).margin(1e-9));
  CHECK(r.axis(X).position_mm - r.actual(X) == Approx(c.offset_mm).margin(0.01));
}

SCENARIO("a shared-limit axis checked from nearer its switch than its rest point ends pull-off away, not tripped",
         "[trust]") {
  // Campaign seed 187208768: a trigger method went back to where it started,
  // inside the switch's hysteresis, with its sensor still active: homed on
  // its shared limit, it tripped hard_limit at once.
  CleanStop c;
  const AxisSettings& s = shared_limit_reapproach(c, 0.2);
  home_and_stop(c);
  // 0.1 mm from the trigger edge (at carriage 0), off the switch coming from above.
  c.before.move(X, c.before.axis(X).position_mm - (c.before.actual(X) - 0.1));
  c.before.run_until([&] { return !c.before.any_moving(); }, 30);
  c.before.step();
  REQUIRE(c.before.actual(X) == Approx(0.1).margin(1e-6));
  REQUIRE_FALSE(c.before.sim().sensor_active(X));
  REQUIRE_FALSE(c.before.status().alarm);
  c.stops = shut_down(c.before);
  REQUIRE(c.stops[X].clean);
  Rig r = restart(c.before, c.stops);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::accepted);
  r.run_for(0.1);
  CHECK_FALSE(r.status().alarm);
  CHECK(r.axis(X).trust == Trust::reference_checked);
  CHECK_FALSE(r.sim().sensor_active(X));
  CHECK(r.axis(X).position_mm == Approx(s.home_position_mm).margin(0.01));  // where a cycle ends
}

SCENARIO("a shared-limit axis whose switch's hysteresis grew holds it active back where it started: led off it, homed, not tripped",
         "[trust]") {
  // Campaign seed 194072538: the approach triggered the shared limit, the
  // check went back to where the axis had rested, inside the switch's
  // hysteresis band, and homed it there with its sensor still active: it
  // tripped hard_limit at once.
  CleanStop c;
  const AxisSettings& s = shared_limit_reapproach(c, 0.02);  // released within the pull-off at the cycle
  home_and_stop(c);
  REQUIRE(c.stops[X].clean);
  REQUIRE_FALSE(c.before.sim().sensor_active(X));
  const double rest = c.before.actual(X);
  // Worn while the machine was off: the band now reaches past the rest point.
  c.before.machine.axes[X].hysteresis_mm = 1.5 * (rest - 0.0) + 0.1;
  Rig r = restart(c.before, c.stops);
  CHECK(refcheck(r, axis_bit(X)) == CommandResult::accepted);
  r.run_for(0.1);
  CHECK_FALSE(r.status().alarm);
  CHECK(r.axis(X).homed);
  CHECK(r.axis(X).trust == Trust::reference_checked);
  CHECK_FALSE(r.sim().sensor_active(X));
  // Pull-off beyond where it released, with the coordinate the cycle gave that place.
  CHECK(r.actual(X) > rest);
  CHECK(r.axis(X).position_mm - r.actual(X) == Approx(c.offset_mm).margin(s.refcheck_tolerance_mm));
}
