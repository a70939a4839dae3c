// An axis is homed only in the frame it was homed in (homing/home_frame.hpp):
// a settings change that moves where its coordinates lie clears its homed
// state before anything moves with them; other changes keep it homed.
#include <catch2/catch.hpp>

#include "rig.hpp"

using namespace rig;

SCENARIO("changing a setting that places the coordinates unhomes the axis", "[home_frame]") {
  const auto unhomes = [](auto change) {
    Rig r;
    REQUIRE(r.home_all());
    REQUIRE(r.axis(0).homed);
    change(r.settings.axes[0]);
    r.step();
    return !r.axis(0).homed && r.status().state == MachineState::not_homed;
  };
  CHECK(unhomes([](AxisSettings& s) { s.home_position_mm = 5; }));
  CHECK(unhomes([](AxisSettings& s) { s.pull_off_mm = 2; }));
  CHECK(unhomes([](AxisSettings& s) { s.direction = Direction::positive; }));
  CHECK(unhomes([](AxisSettings& s) { s.mode = HomingMode::switch_reapproach; }));
  CHECK(unhomes([](AxisSettings& s) { s.sensor_nc = true; }));
}

SCENARIO("a new cam edge unhomes a home cam axis and leaves an axis homed on a switch homed",
         "[home_frame][home_cam]") {
  // Found by a technician: the edge was no part of the frame, so a home cam
  // axis kept coordinates measured from the other edge of its cam.
  Rig r;
  fit_home_cam(r, 50, 10, 20, CamEdge::behind);
  r.settings.axes[1] = typical_axis();  // Y homes on a switch: a cam edge places nothing
  r.step();
  REQUIRE(r.home_all());
  REQUIRE(r.axis(0).homed);
  REQUIRE(r.axis(1).homed);
  r.settings.axes[0].cam_edge = CamEdge::ahead;
  r.settings.axes[1].cam_edge = CamEdge::ahead;
  r.step();
  CHECK_FALSE(r.axis(0).homed);
  CHECK(r.axis(1).homed);
}

SCENARIO("a change that leaves the coordinates where they are keeps the axis homed", "[home_frame]") {
  Rig r;
  REQUIRE(r.home_all());
  r.settings.axes[0].seek_feedrate_mm_per_min = 900;
  r.settings.axes[0].jog_feedrate_mm_per_min = 300;
  r.settings.axes[0].soft_limit_max_mm = 400;
  r.settings.axes[0].max_seek_travel_mm = 250;
  r.run_for(0.1);
  CHECK(r.axis(0).homed);
  CHECK(r.status().state == MachineState::homed);
}

SCENARIO("an axis unhomed by a new home position homes again into the new coordinates", "[home_frame]") {
  Rig r;
  REQUIRE(r.home_all());
  const double rest_mm = r.actual(0);
  r.settings.axes[0].home_position_mm = 5;
  r.step();
  REQUIRE_FALSE(r.axis(0).homed);
  REQUIRE(r.home_all());
  CHECK(r.actual(0) == Approx(rest_mm).margin(1e-3));       // the same place on the machine
  CHECK(r.axis(0).position_mm == Approx(5).margin(1e-9));   // called 5 now
}

SCENARIO("a new home position on a gantry master unhomes its slave too", "[home_frame][gantry]") {
  Rig r;
  r.settings.axes[1] = typical_axis();
  r.settings.axes[1].slave_of = 1;
  r.settings.axes[1].max_misalignment_mm = 2;
  REQUIRE(r.home_all());
  REQUIRE(r.axis(1).homed);
  r.settings.axes[0].home_position_mm = 3;
  r.step();
  CHECK_FALSE(r.axis(0).homed);
  CHECK_FALSE(r.axis(1).homed);
}

SCENARIO("a new switch compensation or pull-off on a gantry slave unhomes its master too", "[home_frame][gantry]") {
  // Found by a technician: the slave alone was unhomed, and its master went on
  // moving the half-homed pair by coordinates at jog feedrate.
  const auto both_unhomed = [](auto change) {
    Rig r;
    r.settings.axes[1] = typical_axis();
    r.settings.axes[1].slave_of = 1;
    r.settings.axes[1].max_misalignment_mm = 2;
    REQUIRE(r.home_all());
    REQUIRE(r.axis(0).homed);
    REQUIRE(r.axis(1).homed);
    change(r.settings.axes[1]);
    r.step();
    return !r.axis(0).homed && !r.axis(1).homed;
  };
  CHECK(both_unhomed([](AxisSettings& s) { s.switch_compensation_mm = -0.3; }));
  CHECK(both_unhomed([](AxisSettings& s) { s.pull_off_mm = 2.01; }));
}

SCENARIO("a frame change of an axis outside any pair leaves the other axes homed", "[home_frame]") {
  Rig r;
  r.settings.axes[1] = typical_axis();
  REQUIRE(r.home_all());
  REQUIRE(r.axis(1).homed);
  r.settings.axes[0].switch_compensation_mm = 0.2;
  r.step();
  CHECK_FALSE(r.axis(0).homed);
  CHECK(r.axis(1).homed);
}
