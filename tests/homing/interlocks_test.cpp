// Motion before and after homing: allowed commands without homing, soft
// limits, shared limit, jog and move, the permit, and the interlock bitmask.
#include <catch2/catch.hpp>

#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

namespace {
void settle(Rig& r) {
  r.run_until([&] { return !r.any_moving() && r.axis(0).phase != Phase::move && r.axis(0).phase != Phase::stopping; }, 60);
}
double max_speed_while_jogging(Rig& r, std::size_t a, int dir, double seconds) {
  double vmax = 0;
  r.jog(a, dir);
  const double end = r.sim().time_s() + seconds;
  while (r.sim().time_s() < end) {
    r.step();
    vmax = std::max(vmax, std::abs(r.axis(a).velocity_mm_per_s));
  }
  r.release_jogs();
  settle(r);
  return vmax;
}
}  // namespace

SCENARIO("before homing, allowed_without_homing = all: jog at full speed and moves", "[interlocks]") {
  Rig r;
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.step();
  CHECK((r.status().interlocks & interlock::not_homed) == 0);
  CHECK(max_speed_while_jogging(r, 0, +1, 1.0) == Approx(10));
  const double x = r.actual(0);
  r.move(0, r.axis(0).position_mm + 5);
  CHECK(r.status().last_command_result == CommandResult::accepted);
  settle(r);
  CHECK(r.actual(0) == Approx(x + 5).margin(1e-9));
}

SCENARIO("before homing, allowed_without_homing = jog reduced: jog at 100 mm/min, no moves", "[interlocks]") {
  Rig r;
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::jog_reduced;
  r.step();
  CHECK((r.status().interlocks & interlock::not_homed) != 0);
  CHECK(max_speed_while_jogging(r, 0, -1, 1.0) == Approx(100.0 / 60));
  r.move(0, 50);
  CHECK(r.status().last_command_result == CommandResult::refused_not_homed);
  WHEN("homed, the jog runs at full speed again") {
    REQUIRE(r.home_all());
    CHECK((r.status().interlocks & interlock::not_homed) == 0);
    CHECK(max_speed_while_jogging(r, 0, +1, 1.0) == Approx(10));
  }
}

SCENARIO("a new module allows only a jog at reduced speed before homing: a move is refused", "[interlocks]") {
  Rig r;
  r.settings.global = GlobalSettings{};  // the engine's defaults, as a new module has them
  r.settings.global.sequence_steps = {axis_bit(0), 0, 0, 0, 0, 0};
  REQUIRE(r.settings.global.allowed_without_homing == AllowedWithoutHoming::jog_reduced);
  r.step();
  CHECK((r.status().interlocks & interlock::not_homed) != 0);
  const double x = r.actual(0);
  r.move(0, r.axis(0).position_mm + 50);
  CHECK(r.status().last_command_result == CommandResult::refused_not_homed);
  settle(r);
  CHECK(r.actual(0) == x);
  // A jog at the axis's full jog feedrate (600 mm/min) runs at 100 mm/min only.
  CHECK(max_speed_while_jogging(r, 0, +1, 1.0) == Approx(100.0 / 60));
  CHECK(r.status().last_command_result == CommandResult::accepted);
  CHECK(r.actual(0) > x + 1);
}

SCENARIO("before homing, allowed_without_homing = none: jog and move refused", "[interlocks]") {
  Rig r;
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::none;
  r.step();
  r.clear_trace();
  r.jog(0, +1);
  r.run_for(0.2);
  r.release_jogs();
  CHECK(r.status().last_command_result == CommandResult::refused_not_homed);
  CHECK(r.trace[0].path_mm == 0);
  r.move(0, 50);
  CHECK(r.status().last_command_result == CommandResult::refused_not_homed);
  CHECK((r.status().interlocks & interlock::not_homed) != 0);
}

SCENARIO("a jog at the registers' maximum feedrate stops at its soft limit when control periods come late",
         "[interlocks][limits][late]") {
  // Campaign seed 2109: a jog at 52,000 mm/min and 43,000 mm/s² cruised at a
  // speed whose stop only fitted half a late period, passed its soft limit
  // and raised soft_limit. Each start of the jog is tried against a late
  // period (up to 20 ms) coming at each of its first periods in turn.
  for (int late_at = 1; late_at <= 12; ++late_at) {
    DYNAMIC_SECTION("the period after " << late_at << " is 19.9 ms long") {
      Rig r;
      AxisSettings& s = r.settings.axes[0];
      s.soft_limits_enable = true;
      s.soft_limit_min_mm = -1;
      s.soft_limit_max_mm = 15;
      REQUIRE(r.home_all());
      s.jog_feedrate_mm_per_min = 52'000;
      s.acceleration_mm_per_s2 = 43'000;
      int period = 0;
      r.next_dt = [&] { return ++period == late_at ? 0.0199 : 0.001; };
      double highest = r.axis(0).position_mm;
      r.jog(0, +1);
      for (int i = 0; i < 400; ++i) {
        r.step();
        highest = std::max(highest, r.axis(0).position_mm);
      }
      r.release_jogs();
      r.run_for(0.1);
      CHECK_FALSE(r.status().alarm);
      CHECK(highest <= 15 + 1e-9);
      CHECK(r.axis(0).position_mm == Approx(15).margin(1e-9));
    }
  }
}

SCENARIO("after homing, soft limits are enforced", "[interlocks][limits]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.soft_limits_enable = true;
  s.soft_limit_min_mm = -1;
  s.soft_limit_max_mm = 20;
  REQUIRE(r.home_all());
  WHEN("jogging toward the limit") {
    r.jog(0, +1);
    r.run_for(4);
    THEN("the jog stops at the limit") {
      CHECK(r.axis(0).position_mm == Approx(20).margin(1e-9));
      CHECK(r.axis(0).velocity_mm_per_s == 0);
      CHECK_FALSE(r.status().alarm);
    }
    THEN("held there, it has ended: the axis reads at rest, not moving") {
      CHECK(r.axis(0).phase == Phase::idle);
      CHECK(r.status().state != MachineState::moving);
      CHECK((r.status().interlocks & interlock::motion_active) == 0);
    }
    r.release_jogs();
    r.step();
    AND_WHEN("pressed again toward the limit") {
      r.clear_trace();
      const auto count = r.status().command_count;
      r.jog(0, +1);
      r.run_for(0.2);
      THEN("it is refused for the soft limit and moves nothing") {
        CHECK(r.status().command_count == count + 1);
        CHECK(r.status().last_command_result == CommandResult::refused_soft_limit);
        CHECK(r.trace[0].path_mm == 0);
      }
      r.release_jogs();
    }
    AND_WHEN("pressed away from the limit") {
      r.jog(0, -1);
      r.run_for(0.2);
      THEN("it runs") {
        CHECK(r.status().last_command_result == CommandResult::accepted);
        CHECK(r.axis(0).position_mm < 20);
      }
      r.release_jogs();
    }
  }
  WHEN("jogging toward the minimum") {
    r.jog(0, -1);
    r.run_for(2);
    r.release_jogs();
    CHECK(r.axis(0).position_mm == Approx(-1).margin(1e-9));
    CHECK_FALSE(r.status().alarm);
  }
  WHEN("moving outside the limits") {
    r.clear_trace();
    r.move(0, 20.5);
    CHECK(r.status().last_command_result == CommandResult::refused_soft_limit);
    r.move(0, -1.5);
    CHECK(r.status().last_command_result == CommandResult::refused_soft_limit);
    r.run_for(0.1);
    CHECK(r.trace[0].path_mm == 0);
  }
  WHEN("moving inside the limits") {
    r.move(0, 19.5);
    CHECK(r.status().last_command_result == CommandResult::accepted);
    CHECK((r.status().interlocks & interlock::motion_active) != 0);
    CHECK(r.status().state == MachineState::moving);
    settle(r);
    CHECK(r.axis(0).position_mm == Approx(19.5).margin(1e-9));
    CHECK(r.actual(0) == Approx(19.5 + 1.05).margin(1e-4));
    CHECK(r.status().state == MachineState::homed);
  }
}

SCENARIO("after homing, a shared home sensor acts as a hard limit", "[interlocks][limits]") {
  Rig r;
  r.settings.axes[0].shared_limit = true;
  REQUIRE(r.home_all());
  CHECK_FALSE(r.status().alarm);  // resting off the sensor after the pull-off: no trip
  r.move(0, -2);
  r.run_until([&] { return r.status().alarm; }, 5);
  CHECK(r.axis(0).alarm.code == AlarmCode::hard_limit);
  CHECK(r.axis(0).alarm.value == Approx(-1.05).margin(0.02));  // tripped at the cam edge
  // Standing on it, reset: bit 9 says why a jog toward it will be refused.
  settle(r);
  r.reset_alarm();
  CHECK(r.status().interlocks & interlock::limit_active);
  WHEN("shared_limit is off the same move is fine") {
    Rig q;
    REQUIRE(q.home_all());
    q.move(0, -2);
    settle(q);
    CHECK_FALSE(q.status().alarm);
    CHECK(q.axis(0).position_mm == Approx(-2).margin(1e-9));
  }
}

SCENARIO("the homing permit", "[interlocks][permit]") {
  Rig r;
  r.settings.global.permit_required = true;
  r.step();
  CHECK((r.status().interlocks & interlock::permit_missing) != 0);
  r.pending.home_all = true;
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_no_permit);
  CHECK_FALSE(r.status().homing);
  r.sim().set_homing_permit(true);
  r.step();
  CHECK((r.status().interlocks & interlock::permit_missing) == 0);
  REQUIRE(r.home_all());
  WHEN("the permit is not required it is ignored") {
    r.settings.global.permit_required = false;
    r.sim().set_homing_permit(false);
    r.step();
    CHECK((r.status().interlocks & interlock::permit_missing) == 0);
    REQUIRE(r.home_all());
  }
}

SCENARIO("the interlock bitmask says what blocks motion", "[interlocks]") {
  Rig r;
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::none;
  r.step();
  CHECK(r.status().interlocks == interlock::not_homed);
  r.pending.home_all = true;
  r.step();
  CHECK(r.status().interlocks == (interlock::not_homed | interlock::homing_active));
  r.run_until([&] { return !r.status().homing; }, 60);
  CHECK(r.status().interlocks == 0);
  r.jog(0, 1);
  r.step();
  r.step();
  CHECK(r.status().interlocks == interlock::motion_active);
  r.release_jogs();
  settle(r);
  CHECK(r.status().interlocks == 0);
  r.sim().set_estop(true);
  r.step();
  CHECK((r.status().interlocks & interlock::estop) != 0);
  CHECK((r.status().interlocks & interlock::alarm_latched) != 0);
  for (int bit = 0; bit < interlock::kCount; ++bit) CHECK_FALSE(interlock_name(bit).empty());
}

SCENARIO("jog and move commands while moving", "[interlocks][commands]") {
  Rig r;
  REQUIRE(r.home_all());
  r.move(0, 50);
  r.step();
  r.jog(0, 1);
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_busy);
  r.release_jogs();
  r.pending.home_all = true;
  r.step();
  CHECK(r.status().last_command_result == CommandResult::refused_busy);
  settle(r);
  CHECK(r.axis(0).position_mm == Approx(50).margin(1e-9));
  r.move(0, std::numeric_limits<double>::quiet_NaN());
  CHECK(r.status().last_command_result == CommandResult::refused_invalid);
  r.jog(0, -1);
  r.run_for(0.5);
  r.release_jogs();
  settle(r);
  CHECK(r.axis(0).position_mm < 50);
  CHECK(r.axis(0).position_mm == Approx(r.actual(0) - 1.05).margin(1e-4));
}

SCENARIO("reset while the cause is still present is refused", "[interlocks][commands]") {
  Rig r;
  r.sim().set_estop(true);
  r.step();
  r.reset_alarm();
  CHECK(r.status().last_command_result == CommandResult::refused_cause_present);
  r.sim().set_estop(false);
  r.step();
  r.reset_alarm();
  CHECK(r.status().last_command_result == CommandResult::accepted);
  CHECK_FALSE(r.status().alarm);
}

SCENARIO("an axis left outside tightened soft limits only jogs back in", "[interlocks][limits]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.soft_limits_enable = true;
  s.soft_limit_min_mm = -1;
  s.soft_limit_max_mm = 20;
  REQUIRE(r.home_all());
  r.move(0, 15);
  settle(r);
  REQUIRE(r.axis(0).position_mm == Approx(15).margin(1e-9));
  s.soft_limit_max_mm = 10;  // tightened: the axis now stands 5 mm outside
  WHEN("jogging further out") {
    r.clear_trace();
    r.jog(0, +1);
    r.run_for(0.5);
    r.release_jogs();
    r.run_for(0.2);
    THEN("nothing moves and no alarm is raised") {
      CHECK(r.trace[0].path_mm == 0);
      CHECK_FALSE(r.status().alarm);
    }
  }
  WHEN("jogging back in") {
    r.jog(0, -1);
    r.run_for(0.5);
    r.release_jogs();
    settle(r);
    THEN("it moves toward the limits without an alarm") {
      CHECK(r.axis(0).position_mm < 15);
      CHECK_FALSE(r.status().alarm);
    }
  }
}
