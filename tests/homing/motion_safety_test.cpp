// Named scenarios for the multi-axis motion-safety rules (issue 13): each one
// was a way to move a machine wrongly before the rules below existed.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "accel_watch.hpp"
#include "homing/gantry.hpp"
#include "homing/settings_check.hpp"
#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

namespace {

// X master, Y software-slaved to it; both sensors' cams end at 0 unless skewed.
Rig software_pair(double slave_edge_mm = 0) {
  Rig r;
  r.settings.axes[1] = typical_axis();
  r.settings.axes[1].slave_of = 1;
  r.settings.axes[1].max_misalignment_mm = 2;
  r.machine.axes[1].sensor_max_mm = slave_edge_mm;
  return r;
}

// Largest change of the carriages' relative position (slave - master) seen
// from the moment the watch starts.
struct RackWatch {
  double rel0 = 0;
  double worst = 0;
  void start(Rig& r) {
    rel0 = r.actual(1) - r.actual(0);
    worst = 0;
    r.on_period = [this](Rig& rr) {
      worst = std::max(worst, std::abs(rr.actual(1) - rr.actual(0) - rel0));
    };
  }
};

// A slave the gantry rules refuse (`bad`, by `rule`) is no pair member: a
// jog, a move and a home-all of X are refused for the settings fault, no
// axis moves (no slave follows, X does not move alone) and X's output never
// switches to a commutator slave.
void refused_everywhere(Rig& r, std::size_t bad, CheckRule rule) {
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.step();
  const auto fault = check_axis(r.settings, bad);
  REQUIRE(fault);
  CHECK(fault->rule == rule);
  CHECK(gantry_master(r.settings, bad) < 0);
  bool commutator = false;
  r.on_period = [&](Rig& rr) { commutator = commutator || rr.engine.outputs().axes[0].commutator_output; };
  r.clear_trace();
  r.jog(0, +1);
  r.run_for(0.5);
  r.release_jogs();
  CHECK(r.status().last_command_result == CommandResult::refused_settings_fault);
  CHECK(r.trace[bad].path_mm == 0);  // it did not follow the jog
  r.move(0, 50);
  CHECK(r.status().last_command_result == CommandResult::refused_settings_fault);
  r.pending.home_all = true;
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_settings_fault);
  r.run_for(0.2);
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    INFO(kAxisUpper[a] << " moved " << r.trace[a].path_mm << " mm");
    CHECK(r.trace[a].path_mm == 0);
  }
  CHECK_FALSE(commutator);
  r.on_period = nullptr;
}

}  // namespace

SCENARIO("a slave homes with its master's motion settings: its own direction, feedrates, mode and pre-move are ignored",
         "[gantry][safety]") {
  Rig r = software_pair(0.8);
  AxisSettings& y = r.settings.axes[1];
  y.direction = Direction::positive;
  y.seek_feedrate_mm_per_min = 3000;
  y.latch_feedrate_mm_per_min = 500;
  y.mode = HomingMode::switch_reapproach;
  y.pre_move_mode = PreMove::always;
  y.max_seek_travel_mm = 5;
  y.acceleration_mm_per_s2 = 2000;  // the pair moves with the lower one (X's 500)
  REQUIRE_FALSE(check_axis(r.settings, 1));
  RackWatch rack;
  rack.start(r);
  REQUIRE(r.home_all());
  CHECK(rack.worst <= 0.8 + 0.1);  // the squaring, plus the two sides braking a period apart
  // Square by the sensors: each side pulled off its own release edge.
  CHECK(r.actual(0) == Approx(rest_point_mm(r.settings.axes[0], last_release_mm(r, 0))).margin(1e-3));
  CHECK(r.actual(1) == Approx(rest_point_mm(r.settings.axes[0], last_release_mm(r, 1))).margin(1e-3));
  CHECK(r.axis(1).position_mm == Approx(r.axis(0).position_mm).margin(1e-3));
}

SCENARIO("a gantry with one side starting on its sensor and the other side's sensor dead stops within max_misalignment",
         "[gantry][safety]") {
  for (std::size_t on_sensor : {0u, 1u}) {
    Rig r = software_pair();
    r.machine.axes[on_sensor].actual_position_mm = -3;  // on its cam
    r.machine.axes[1 - on_sensor].actual_position_mm = -3;
    r.machine.axes[1 - on_sensor].fault = sim::Fault::sensor_stuck_inactive;
    RackWatch rack;
    rack.start(r);
    r.home_all();
    r.run_until([&] { return !r.any_moving(); }, 5);
    CHECK(r.status().alarm);
    CHECK(r.axis(1).alarm.code == AlarmCode::misalignment);
    CHECK(rack.worst <= 2 + 0.05);
    CHECK_FALSE(r.axis(0).homed);
  }
}

SCENARIO("pre-move if the sensor is active is decided for the pair", "[gantry][safety]") {
  Rig r = software_pair(-4);  // the slave's cam ends 4 mm lower: only the slave starts on it
  r.settings.axes[0].pre_move_mode = PreMove::if_sensor_active;
  r.settings.axes[0].pre_move_distance_mm = 5;
  r.machine.axes[0].actual_position_mm = 0.5;
  r.machine.axes[1].actual_position_mm = -4.5;  // 0.5 mm onto its cam
  r.settings.axes[1].max_misalignment_mm = 5;
  RackWatch rack;
  rack.start(r);
  REQUIRE(r.home_all());
  CHECK(r.saw(0, Phase::pre_move));
  CHECK(r.saw(1, Phase::pre_move));
  CHECK(rack.worst <= 1 + 0.1);  // the squaring (1 mm of skew), plus the sides braking a period apart
}

SCENARIO("a stuck-active slave sensor stops the pair within max_misalignment", "[gantry][safety]") {
  Rig r = software_pair();
  r.machine.axes[1].fault = sim::Fault::sensor_stuck_active;
  RackWatch rack;
  rack.start(r);
  r.home_all();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(r.status().alarm);
  CHECK(rack.worst <= 2 + 0.05);
}

SCENARIO("a software-slaved gantry whose slave seeks on alone brakes in time to stay within max_misalignment",
         "[gantry][safety]") {
  // The slave's sensor is dead: the master stops on its own trigger while the
  // slave seeks on at 20 mm/s. Stopping takes it 0.4 mm, so the guard must
  // brake it before the skew is 2 mm, not when it is.
  for (const bool late : {false, true}) {
    DYNAMIC_SECTION((late ? "with periods 10 ms late" : "1 ms periods")) {
      Rig r = software_pair();
      r.machine.axes[1].fault = sim::Fault::sensor_stuck_inactive;
      int n = 0;
      if (late) r.next_dt = [&] { return (++n % 7 == 0) ? 0.011 : 0.001; };
      RackWatch rack;
      rack.start(r);
      r.home_all();
      r.run_until([&] { return !r.any_moving(); }, 5);
      CHECK(r.axis(1).alarm.code == AlarmCode::misalignment);
      CHECK(rack.worst > 1);  // the slave did run on past its master
      CHECK(rack.worst <= r.settings.axes[1].max_misalignment_mm + 1e-9);
    }
  }
}

SCENARIO("after an alarm the pair brakes with the lower of the two accelerations", "[gantry][safety]") {
  Rig r = software_pair();
  r.settings.axes[1].acceleration_mm_per_s2 = 100;  // the slave's drive can do less
  r.settings.axes[0].seek_feedrate_mm_per_min = 600;
  REQUIRE_FALSE(check_axis(r.settings, 1));
  r.pending.home_all = true;
  r.step();
  r.run_until([&] { return r.axis(1).phase == Phase::seek && r.axis(1).velocity_mm_per_s < -9.9; }, 5);
  AccelWatch acc;
  acc.start(r);
  r.pending.abort = true;
  r.step();
  r.run_until([&] { return !r.any_moving(); }, 5);
  INFO(acc.describe(0) << "\n" << acc.describe(1));
  CHECK(acc.within(0));
  CHECK(acc.within(1));
  CHECK(motion_settings(r.settings).axes[0].acceleration_mm_per_s2 == 100);
}

SCENARIO("the seek brakes in time and comes to rest at max_seek_travel", "[safety]") {
  Rig r;
  r.machine.axes[0].fault = sim::Fault::sensor_stuck_inactive;
  r.settings.axes[0].max_seek_travel_mm = 30;
  const double x0 = r.actual(0);
  AccelWatch acc;
  acc.start(r);
  r.home_all();
  CHECK(r.axis(0).alarm.code == AlarmCode::sensor_not_found);
  INFO(acc.describe(0));
  CHECK(acc.within(0));
  CHECK(x0 - r.actual(0) == Approx(30).margin(1e-6));
}

SCENARIO("the seek end stays within the acceleration when control periods come late", "[safety]") {
  Rig r;
  r.machine.axes[0].fault = sim::Fault::sensor_stuck_inactive;
  r.settings.axes[0].max_seek_travel_mm = 30;
  int n = 0;
  r.next_dt = [&] { return (++n % 7 == 0) ? 0.009 : 0.001; };
  AccelWatch acc;
  acc.start(r);
  r.home_all();
  CHECK(r.axis(0).alarm.code == AlarmCode::sensor_not_found);
  INFO(acc.describe(0));
  CHECK(acc.within(0));
}

SCENARIO("the back-off brakes in time and comes to rest at max_backoff", "[safety]") {
  // A sensor that never releases: the back-off runs out at max_backoff
  // (10 mm at the latch feedrate, 1 mm/s) and must brake into that end,
  // not stop dead on it (1 mm/s in one 1 ms period would be twice the 500 mm/s²).
  for (const bool late : {false, true}) {
    DYNAMIC_SECTION((late ? "with late periods" : "1 ms periods")) {
      Rig r;
      r.machine.axes[0].fault = sim::Fault::sensor_stuck_active;
      int n = 0;
      if (late) r.next_dt = [&] { return (++n % 7 == 0) ? 0.009 : 0.001; };
      const double x0 = r.actual(0);
      AccelWatch acc;
      acc.start(r);
      r.home_all(30);
      CHECK(r.axis(0).alarm.code == AlarmCode::not_released);
      CHECK(r.axis(0).alarm.phase == Phase::back_off);
      INFO(acc.describe(0));
      CHECK(acc.within(0));
      CHECK(r.actual(0) - x0 == Approx(r.settings.axes[0].max_backoff_mm).margin(1e-6));
    }
  }
}

SCENARIO("a pull-off that a late period reaches brakes onto its target within the acceleration", "[safety][late]") {
  // How many periods the pull-off takes when every period is on time.
  std::uint64_t pull_off_periods = 0;
  {
    Rig r;
    r.on_period = [&](Rig& rr) { pull_off_periods += rr.axis(0).phase == Phase::pull_off; };
    REQUIRE(r.home_all());
    REQUIRE(pull_off_periods > 10);
  }
  // One period 10 ms late, at each moment of the pull-off in turn.
  for (std::uint64_t late_at = 1; late_at < pull_off_periods; ++late_at) {
    Rig r;
    std::uint64_t in_pull_off = 0;
    bool was_late = false;
    r.next_dt = [&] {
      if (r.axis(0).phase != Phase::pull_off || ++in_pull_off != late_at) return 0.001;
      was_late = true;
      return 0.011;
    };
    AccelWatch acc;
    acc.start(r);
    const bool homed = r.home_all();
    INFO("late period at pull-off period " << late_at << ", " << acc.describe(0));
    CHECK(was_late);
    CHECK(homed);
    CHECK(acc.within(0));
    CHECK(r.actual(0) == Approx(1.05).margin(edge_tolerance_mm(r.settings.axes[0], 0.001)));
  }
}

SCENARIO("an absolute axis in no sequence step takes its coordinate from its encoder", "[sequence][safety]") {
  Rig r;
  r.settings.axes[3] = typical_axis();
  r.settings.axes[3].mode = HomingMode::absolute;
  r.settings.axes[3].home_position_mm = 10;  // encoder offset
  r.machine.axes[3].actual_position_mm = 43;
  r.machine.axes[3].absolute_offset_mm = 5;
  REQUIRE(r.home_all());
  CHECK(r.axis(3).homed);
  CHECK(r.axis(3).position_mm == Approx(43 + 5 - 10).margin(1e-9));
  CHECK(r.trace[3].path_mm == 0);
}

SCENARIO("an unsequenced absolute axis without a valid encoder ends the cycle in an encoder fault", "[sequence][safety]") {
  Rig r;
  r.settings.axes[3] = typical_axis();
  r.settings.axes[3].mode = HomingMode::absolute;
  r.tweak_inputs = [](Inputs& in) { in.axes[3].absolute_valid = false; };
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(3).alarm.code == AlarmCode::encoder_fault);
  CHECK_FALSE(r.axis(3).homed);
}

SCENARIO("a disabled slave or a slave of a slave is refused everywhere and never follows its master", "[gantry][safety]") {
  for (int variant = 0; variant < 3; ++variant) {
    Rig r;
    if (variant == 0) {
      r.settings.axes[1].mode = HomingMode::disabled;  // Y disabled, yet named slave of X
      r.settings.axes[1].slave_of = 1;
    } else if (variant == 1) {
      r.settings.axes[1] = typical_axis();
      r.settings.axes[1].slave_of = 1;  // Y slave of X
      r.settings.axes[2] = typical_axis();
      r.settings.axes[2].slave_of = 2;  // Z slave of Y
    } else {
      r.settings.axes[1] = typical_axis();  // every other gantry rule holds
      r.settings.axes[1].mode = HomingMode::disabled;  // Y disabled, yet named X's commutator slave
      r.settings.axes[1].slave_of = 1;
      r.settings.axes[1].slave_mode = SlaveMode::external_commutator;
    }
    const std::size_t bad = variant == 1 ? 2 : 1;
    INFO("variant " << variant);
    refused_everywhere(r, bad, variant == 1 ? CheckRule::slave_of_slave : CheckRule::disabled_in_gantry);
  }
}

SCENARIO("a slave of a disabled, manual or absolute axis, or a second slave on one master, is refused and never follows its master's jog",
         "[gantry][safety]") {
  struct Case {
    const char* what;
    HomingMode master_mode;
    bool second_slave;
    CheckRule rule;
  };
  const Case cases[] = {
      {"slave of a disabled axis", HomingMode::disabled, false, CheckRule::disabled_in_gantry},
      {"slave of a manual axis", HomingMode::manual, false, CheckRule::slave_invalid},
      {"slave of an absolute axis", HomingMode::absolute, false, CheckRule::slave_invalid},
      {"second slave of a switch-homing axis", HomingMode::switch_release, true, CheckRule::slave_invalid},
  };
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.what) {
      Rig r;
      r.settings.axes[0].mode = c.master_mode;
      r.settings.axes[1] = typical_axis();
      r.settings.axes[1].slave_of = 1;  // Y slave of X
      std::size_t bad = 1;
      if (c.second_slave) {
        r.settings.axes[2] = typical_axis();
        r.settings.axes[2].slave_of = 1;  // Z too: X already has Y
        bad = 2;
        CHECK(gantry_master(r.settings, 1) == 0);
      }
      refused_everywhere(r, bad, c.rule);
    }
  }
}

SCENARIO("a hard-limit trip can be recovered with alarm_clears_homed off: reset, then jog away only",
         "[alarms][limits][safety]") {
  Rig r;
  r.settings.global.alarm_clears_homed = false;
  r.settings.axes[0].shared_limit = true;
  REQUIRE(r.home_all());
  r.jog(0, -1);  // toward the sensor (homing direction negative)
  r.run_until([&] { return r.status().alarm; }, 10);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  REQUIRE(r.axis(0).alarm.code == AlarmCode::hard_limit);
  REQUIRE(r.sim().sensor_active(0));
  r.reset_alarm();
  CHECK(r.status().last_command_result == CommandResult::accepted);
  r.run_for(0.1);
  CHECK_FALSE(r.status().alarm);  // not re-latched while still on the sensor
  const double x = r.actual(0);
  r.jog(0, -1);  // further onto the sensor: refused
  r.run_for(0.2);
  r.release_jogs();
  CHECK(r.status().last_command_result == CommandResult::refused_hard_limit);
  CHECK(r.actual(0) == x);
  r.jog(0, +1);  // away: allowed until it releases, and on
  r.run_until([&] { return !r.sim().sensor_active(0); }, 10);
  r.run_for(0.2);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK_FALSE(r.status().alarm);
  CHECK(r.actual(0) > x);
  CHECK_FALSE(r.sim().sensor_active(0));
  WHEN("the axis later runs onto the sensor again") {
    r.jog(0, -1);
    r.run_until([&] { return r.status().alarm; }, 10);
    r.release_jogs();
    CHECK(r.axis(0).alarm.code == AlarmCode::hard_limit);
  }
}

SCENARIO("a shared limit whose rest after pull-off is still on the sensor is refused, not homed", "[limits][safety]") {
  GIVEN("no pull-off: refused by the rule set") {
    AxisSettings s = typical_axis();
    s.shared_limit = true;
    s.pull_off_mm = 0;
    Settings all;
    all.axes[0] = s;
    const auto f = check_axis(all, 0);
    REQUIRE(f);
    CHECK(f->rule == CheckRule::shared_limit_rests_on_sensor);
  }
  GIVEN("a re-approach edge and a pull-off shorter than the hysteresis") {
    Rig r;
    r.settings.axes[0].mode = HomingMode::switch_reapproach;
    r.settings.axes[0].shared_limit = true;
    r.settings.axes[0].pull_off_mm = 0.02;
    r.machine.axes[0].hysteresis_mm = 0.1;
    CHECK_FALSE(r.home_all());
    CHECK(r.axis(0).alarm.code == AlarmCode::not_released);
    CHECK(r.axis(0).alarm.phase == Phase::assign);
    CHECK_FALSE(r.axis(0).homed);
    CHECK(describe_alarm(0, r.axis(0).alarm, r.settings).find("raise pull_off") != std::string::npos);
  }
}

SCENARIO("a push longer than the back-off can release is refused before any motion", "[safety]") {
  Rig r;
  r.settings.axes[0].mode = HomingMode::pushing_release;
  r.settings.axes[0].push_distance_mm = 12;  // max_backoff 10
  const auto f = check_axis(r.settings, 0);
  REQUIRE(f);
  CHECK(f->rule == CheckRule::backoff_too_short);
  r.clear_trace();
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::settings_fault);
  CHECK(r.trace[0].path_mm == 0);
}

SCENARIO("an unsequenced axis whose home position lies outside its soft limits is refused before any motion",
         "[sequence][safety]") {
  Rig r;
  r.settings.axes[2] = typical_axis();  // Z, in no sequence step
  r.settings.axes[2].soft_limits_enable = true;
  r.settings.axes[2].home_position_mm = 600;  // limits [-1, 500]
  r.clear_trace();
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(2).alarm.code == AlarmCode::settings_fault);
  CHECK(r.status().last_command_result == CommandResult::refused_settings_fault);
  for (std::size_t a = 0; a < kAxisCount; ++a) CHECK(r.trace[a].path_mm == 0);
}

SCENARIO("a gantry that could not stop within max_misalignment is refused", "[gantry][safety]") {
  Rig r = software_pair();
  r.settings.axes[0].jog_feedrate_mm_per_min = 6000;  // 100 mm/s: 10 mm to stop at 500 mm/s²
  const auto f = check_axis(r.settings, 1);
  REQUIRE(f);
  CHECK(f->rule == CheckRule::gantry_stop_too_long);
  CHECK(describe_fault(*f, r.settings).find("max_misalignment") != std::string::npos);
}

SCENARIO("the check sizes a gantry's stop with the pair's lower acceleration", "[gantry][safety]") {
  // The seek (20 mm/s) stops in 0.4 mm at 500 mm/s², in 4 mm at 50 mm/s²;
  // max_misalignment is 2: refused whichever side has the weaker drive.
  for (const std::size_t weak : {std::size_t{1}, std::size_t{0}}) {
    DYNAMIC_SECTION((weak == 1 ? "the slave's drive is the weaker" : "the master's drive is the weaker")) {
      Rig r = software_pair();
      r.settings.axes[weak].acceleration_mm_per_s2 = 50;
      const auto f = check_axis(r.settings, 1);
      REQUIRE(f);
      CHECK(f->rule == CheckRule::gantry_stop_too_long);
      CHECK(f->value == Approx(4.0));
      r.clear_trace();
      CHECK_FALSE(r.home_all());
      CHECK(r.status().last_command_result == CommandResult::refused_settings_fault);
      CHECK(r.trace[0].path_mm == 0);
      CHECK(r.trace[1].path_mm == 0);
    }
  }
  GIVEN("both drives at 500 mm/s²") { CHECK_FALSE(check_axis(software_pair().settings, 1)); }
}

SCENARIO("the check accepts a slave whatever its own values of the settings it inherits from its master",
         "[gantry][safety]") {
  // Each value is refused on an axis of its own; on a slave the master's
  // value is the one used, so the pair homes.
  struct Case {
    const char* what;
    std::function<void(AxisSettings&)> spoil;
  };
  const std::vector<Case> cases{
      {"no seek feedrate", [](AxisSettings& s) { s.seek_feedrate_mm_per_min = 0; }},
      {"latch not slower than seek", [](AxisSettings& s) { s.latch_feedrate_mm_per_min = 1200; }},
      {"no max seek travel", [](AxisSettings& s) { s.max_seek_travel_mm = 0; }},
      {"a max stop distance the seek cannot keep", [](AxisSettings& s) { s.max_stop_distance_mm = 0.1; }},
      {"no max back-off", [](AxisSettings& s) { s.max_backoff_mm = 0; }},
      {"a pre-move without distance",
       [](AxisSettings& s) {
         s.pre_move_mode = PreMove::always;
         s.pre_move_distance_mm = 0;
       }},
      {"inverted soft limits",
       [](AxisSettings& s) {
         s.soft_limits_enable = true;
         s.soft_limit_min_mm = 600;
       }},
      {"a home position outside its soft limits",
       [](AxisSettings& s) {
         s.soft_limits_enable = true;
         s.home_position_mm = -50;
       }},
  };
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.what) {
      Settings lone;
      lone.axes[0] = typical_axis();
      c.spoil(lone.axes[0]);
      REQUIRE(check_axis(lone, 0));
      Rig r = software_pair(0.5);
      c.spoil(r.settings.axes[1]);
      const auto f = check_axis(r.settings, 1);
      INFO((f ? describe_fault(*f, r.settings) : std::string("accepted")));
      CHECK_FALSE(f);
      REQUIRE(r.home_all());
      CHECK(r.axis(1).homed);
      CHECK(r.axis(1).position_mm == Approx(r.axis(0).position_mm).margin(1e-3));
    }
  }
}

SCENARIO("a jog held at power-up does not move until released and pressed again", "[safety]") {
  Rig r;
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.jog(0, +1);
  r.run_for(0.3);
  CHECK(r.trace[0].path_mm == 0);
  r.release_jogs();
  r.run_for(0.05);
  r.jog(0, +1);
  r.run_for(0.3);
  CHECK(r.trace[0].path_mm > 0);
}

SCENARIO("an abort that comes with starts in the same period starts nothing and says why", "[safety][commands]") {
  GIVEN("a machine at rest, allowed to jog and move before homing") {
    Rig r;
    r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
    r.step();
    const auto count_before = r.status().command_count;
    WHEN("home-all, a move, a jog press and a reference check arrive with an abort") {
      r.pending.home_all = true;
      r.pending.abort = true;
      r.pending.move_axes = axis_bit(0);
      r.pending.move_target_mm[0] = 50;
      r.pending.refcheck_axes = axis_bit(2);
      r.held.jog[1] = 1;
      r.step();
      THEN("nothing moves, then or later while the jog stays held, and each start is answered cancelled_by_abort") {
        CHECK_FALSE(r.status().homing);
        CHECK(r.status().last_command_result == CommandResult::cancelled_by_abort);
        CHECK(r.status().command_count == count_before + 5);  // the abort and four starts
        for (int i = 0; i < 200; ++i) {
          r.step();
          for (std::size_t a = 0; a < kAxisCount; ++a) REQUIRE(r.axis(a).velocity_mm_per_s == 0);
        }
        CHECK_FALSE(r.status().homing);
        AND_THEN("a new press or a new home-all after the abort works as usual") {
          r.held.jog[1] = 0;
          r.step();
          r.pending.home_all = true;
          r.step();
          CHECK(r.status().homing);
          CHECK(r.status().last_command_result == CommandResult::accepted);
        }
      }
    }
  }
}

SCENARIO("a disabled axis is refused a jog and a move and never moves, whatever allowed_without_homing lets unhomed axes do",
         "[safety]") {
  Rig r;
  r.settings.axes[2] = typical_axis();  // feedrates and all: only its mode says it is not fitted
  r.settings.axes[2].mode = HomingMode::disabled;
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.step();
  r.clear_trace();
  r.jog(2, +1);
  r.run_for(0.3);
  r.release_jogs();
  CHECK(r.status().last_command_result == CommandResult::refused_invalid);
  r.move(2, 10);
  CHECK(r.status().last_command_result == CommandResult::refused_invalid);
  r.run_for(0.3);
  CHECK(r.trace[2].path_mm == 0);
  // An enabled unhomed axis beside it may (allowed_without_homing all).
  r.jog(0, +1);
  r.run_for(0.1);
  r.release_jogs();
  CHECK(r.status().last_command_result == CommandResult::accepted);
  CHECK(r.trace[0].path_mm > 0);
}
