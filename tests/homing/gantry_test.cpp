// Gantry topologies: hardware-slaved (one axis, pushing), software-slaved
// squaring (slave_of, slave_mode 0) and an external commutator (slave_mode 1).
#include <catch2/catch.hpp>

#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

namespace {

// X master, Y its software-slaved second motor.
Rig software_gantry(double slave_start_mm, double compensation_mm = 0) {
  Rig r;
  r.settings.axes[1] = typical_axis();
  r.settings.axes[1].slave_of = 1;
  r.settings.axes[1].slave_mode = SlaveMode::own_output;
  r.settings.axes[1].max_misalignment_mm = 2;
  r.settings.axes[1].switch_compensation_mm = compensation_mm;
  r.machine.axes[1].actual_position_mm = slave_start_mm;
  return r;
}

Rig commutator_gantry(double slave_start_mm, double compensation_mm = 0) {
  Rig r = software_gantry(slave_start_mm, compensation_mm);
  r.settings.axes[1].slave_mode = SlaveMode::external_commutator;
  r.machine.commutator_slave[0] = 1;
  return r;
}

}  // namespace

SCENARIO("hardware-slaved gantry: one axis, the pushing mode aligns both motors against the stop",
         "[gantry]") {
  Rig r;
  r.settings.axes[0].mode = HomingMode::pushing_release;
  r.settings.axes[0].push_distance_mm = 2;
  r.machine.axes[0].hard_stop_min_mm = -1;
  REQUIRE(r.home_all());
  CHECK(r.actual(0) == Approx(1.05).margin(1e-4));
  CHECK(r.axis(0).position_mm == Approx(0).margin(1e-9));
}

SCENARIO("software-slaved gantry with a skewed slave ends square", "[gantry]") {
  for (double skew : {1.5, -1.5, 0.0}) {
    DYNAMIC_SECTION("slave starts " << skew << " mm off") {
      Rig r = software_gantry(100 + skew);
      r.clear_trace();
      REQUIRE(r.home_all());
      const double tol = edge_tolerance_mm(r.settings.axes[0], r.dt_s);
      THEN("each motor found its own edge and both rest at pull-off from it") {
        CHECK(r.saw(0, Phase::back_off));
        CHECK(r.saw(1, Phase::back_off));
        CHECK(last_release_mm(r, 0) == Approx(0.05).margin(1e-9));
        CHECK(last_release_mm(r, 1) == Approx(0.05).margin(1e-9));
        CHECK(r.actual(0) == Approx(1.05).margin(tol));
        CHECK(r.actual(1) == Approx(1.05).margin(tol));
        CHECK(r.axis(0).position_mm == Approx(0).margin(1e-9));
        CHECK(r.axis(1).position_mm == Approx(0).margin(1e-9));
        CHECK(r.axis(1).homed);
      }
      THEN("the first to trigger waited for the other") {
        const std::size_t first = skew > 0 ? 0 : 1;
        if (skew != 0) CHECK(r.saw(first, Phase::waiting));
      }
    }
  }
}

SCENARIO("software-slaved gantry: the switch compensation squares a misplaced slave sensor", "[gantry]") {
  // Y's sensor is mounted 0.5 mm further out: its edge is at 0.55.
  Rig r = software_gantry(100, -0.5);
  r.machine.axes[1].sensor_max_mm = 0.5;
  REQUIRE(r.home_all());
  const double tol = edge_tolerance_mm(r.settings.axes[0], r.dt_s);
  CHECK(last_release_mm(r, 1) == Approx(0.55).margin(1e-9));
  CHECK(r.actual(1) == Approx(rest_point_mm(r.settings.axes[1], 0.55, -0.5)).margin(tol));
  CHECK(r.actual(1) - r.actual(0) == Approx(0).margin(2 * tol));
}

SCENARIO("software-slaved gantry stays square when the two edges are found at different times",
         "[gantry]") {
  // A wide hysteresis on the master's sensor: the master backs off 0.5 mm
  // longer, so the slave is assigned well before the master.
  Rig r = software_gantry(100);
  r.machine.axes[0].hysteresis_mm = 0.5;
  REQUIRE(r.home_all());
  const double tol = edge_tolerance_mm(r.settings.axes[0], r.dt_s);
  CHECK(r.actual(0) == Approx(1.5).margin(tol));
  CHECK(r.actual(1) == Approx(1.05).margin(tol));
  CHECK(r.axis(1).position_mm == Approx(0).margin(1e-9));
  CHECK(r.axis(1).position_mm == Approx(true_position_mm(r, 1, 1.05)).margin(tol));
}

SCENARIO("after squaring, jogging the master moves the slave with it", "[gantry]") {
  Rig r = software_gantry(101);
  REQUIRE(r.home_all());
  const double x0 = r.actual(0), y0 = r.actual(1);
  r.jog(0, +1);
  r.run_for(1.0);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK(r.actual(0) - x0 > 5);
  CHECK(r.actual(1) - y0 == Approx(r.actual(0) - x0).margin(1e-9));
  CHECK(r.axis(1).position_mm == Approx(r.axis(0).position_mm).margin(1e-9));
  WHEN("the master moves to a target") {
    r.move(0, 25);
    r.run_until([&] { return !r.any_moving() && r.axis(0).phase == Phase::idle; }, 10);
    CHECK(r.axis(0).position_mm == Approx(25).margin(1e-9));
    CHECK(r.axis(1).position_mm == Approx(25).margin(1e-9));
    CHECK(r.actual(1) - r.actual(0) == Approx(y0 - x0).margin(1e-9));
  }
  WHEN("the slave itself is commanded") {
    r.move(1, 25);
    CHECK(r.status().last_command_result == CommandResult::refused_slave_axis);
  }
}

SCENARIO("homing the master alone homes its slave too, the slave's own sequence bit is ignored",
         "[gantry]") {
  Rig r = software_gantry(100.5);
  r.settings.global.sequence_steps = {axis_bit(1), axis_bit(0), 0, 0, 0, 0};
  GIVEN("home one axis") {
    REQUIRE(r.home_axes(axis_bit(0)));
    CHECK(r.axis(0).homed);
    CHECK(r.axis(1).homed);
    CHECK(r.actual(1) == Approx(1.05).margin(1e-4));
  }
  GIVEN("home all with the slave in step 1 and the master in step 2") {
    int slave_step = 0;
    r.on_period = [&](Rig& rr) {
      if (rr.axis(1).phase == Phase::seek && !slave_step) slave_step = rr.status().sequence_step;
    };
    REQUIRE(r.home_all());
    CHECK(slave_step == 2);
    CHECK(r.actual(1) == Approx(1.05).margin(1e-4));
  }
}

SCENARIO("external commutator: the master is held while the slave finds its own edge", "[gantry]") {
  Rig r = commutator_gantry(100.8);
  double x_when_master_assigned = 0;
  bool commutator_seen = false, master_moved_while_aligning = false;
  r.on_period = [&](Rig& rr) {
    const bool aligning = rr.axis(1).phase == Phase::align_slave || (x_when_master_assigned != 0 &&
                          rr.axis(1).phase != Phase::waiting && rr.axis(1).phase != Phase::done);
    if (rr.axis(0).phase == Phase::waiting && x_when_master_assigned == 0 && rr.axis(0).homed)
      x_when_master_assigned = rr.simulator->actual_position_mm(0);
    if (rr.engine.outputs().axes[0].commutator_output) commutator_seen = true;
    if (aligning && x_when_master_assigned != 0 &&
        rr.simulator->actual_position_mm(0) != x_when_master_assigned)
      master_moved_while_aligning = true;
  };
  r.clear_trace();
  REQUIRE(r.home_all());
  const double tol = edge_tolerance_mm(r.settings.axes[0], r.dt_s);
  CHECK(commutator_seen);
  CHECK_FALSE(master_moved_while_aligning);
  CHECK(r.saw(1, Phase::align_slave));
  CHECK_FALSE(r.engine.outputs().axes[0].commutator_output);  // switched back
  CHECK(r.actual(0) == Approx(1.05).margin(tol));
  CHECK(r.actual(1) == Approx(1.05).margin(tol));  // square
  CHECK(r.axis(1).position_mm == Approx(0).margin(1e-9));
  CHECK(r.axis(0).homed);
  CHECK(r.axis(1).homed);
  WHEN("the master jogs afterwards the slave follows") {
    const double x0 = r.actual(0), y0 = r.actual(1);
    r.jog(0, +1);
    r.run_for(0.5);
    r.release_jogs();
    r.run_until([&] { return !r.any_moving(); }, 5);
    CHECK(r.actual(1) - y0 == Approx(r.actual(0) - x0).margin(1e-9));
  }
}

SCENARIO("external commutator: the switch compensation is applied by the slave", "[gantry]") {
  Rig r = commutator_gantry(100, 0.2);
  REQUIRE(r.home_all());
  const double tol = edge_tolerance_mm(r.settings.axes[0], r.dt_s);
  CHECK(r.actual(1) == Approx(rest_point_mm(r.settings.axes[0], 0.05, 0.2)).margin(tol));
  CHECK(r.actual(0) == Approx(1.05).margin(tol));
}

SCENARIO("external commutator: a skew beyond max misalignment is an alarm", "[gantry]") {
  Rig r = commutator_gantry(103);
  r.home_all();
  CHECK(r.axis(1).alarm.code == AlarmCode::misalignment);
  CHECK_FALSE(r.engine.outputs().axes[0].commutator_output);
  CHECK_FALSE(r.axis(1).homed);
}

SCENARIO("software-slaved slave whose sensor never triggers is caught by the misalignment bound",
         "[gantry]") {
  Rig r = software_gantry(100);
  r.machine.axes[1].fault = sim::Fault::sensor_stuck_inactive;
  r.home_all();
  CHECK(r.axis(1).alarm.code == AlarmCode::misalignment);
  // The slave went no further than max misalignment plus its stop (and a period each for seeing
  // the trigger and the bound) past the master's trigger.
  CHECK(r.actual(1) >= -2 - 0.4 - 2 * 0.02 - 1e-9);
}
