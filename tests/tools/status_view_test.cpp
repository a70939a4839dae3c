// homingctl status --progress: the bound of each bar is the one the engine
// holds the axis to in that phase (homing/gantry.hpp, settings_check.hpp).
#include <catch2/catch.hpp>

#include <string>

#include "homing/gantry.hpp"
#include "status_view.hpp"

namespace {

homing::Settings gantry_xy(homing::SlaveMode mode) {
  homing::Settings s;
  for (std::size_t a : {0u, 1u}) {
    homing::AxisSettings& x = s.axes[a];
    x.mode = homing::HomingMode::switch_release;
    x.seek_feedrate_mm_per_min = 1200;
    x.latch_feedrate_mm_per_min = 60;
    x.acceleration_mm_per_s2 = 500;
    x.max_seek_travel_mm = 300;
    x.max_misalignment_mm = 2;
  }
  s.axes[1].slave_of = 1;  // Y follows X
  s.axes[1].slave_mode = mode;
  return s;
}

std::string progress_of_y(const homing::Settings& settings) {
  homingctl::StatusView view;
  view.homing = true;
  view.axes[1].phase = homing::Phase::seek;
  view.axes[1].busy = true;
  view.axes[1].phase_distance = 1;
  return homingctl::render_status(view, settings, /*progress=*/true);
}

}  // namespace

TEST_CASE("the seek bar of an external-commutator slave is bounded by max_misalignment, as the engine bounds it") {
  const homing::Settings settings = gantry_xy(homing::SlaveMode::external_commutator);
  REQUIRE(homing::is_commutator_slave(settings, 1));
  CHECK_THAT(progress_of_y(settings), Catch::Contains("seek 1.000 / 2 mm"));
}

TEST_CASE("the seek bar of a slave on its own output is bounded by its master's max_seek_travel") {
  const homing::Settings settings = gantry_xy(homing::SlaveMode::own_output);
  REQUIRE_FALSE(homing::is_commutator_slave(settings, 1));
  CHECK_THAT(progress_of_y(settings), Catch::Contains("seek 1.000 / 300 mm"));
}

TEST_CASE("homingctl status sends the technician to the wiring when both limit switches of an axis read active") {
  homing::Settings settings = gantry_xy(homing::SlaveMode::own_output);
  settings.axes[0].limits_fitted = true;
  settings.axes[1].limits_fitted = true;
  homingctl::StatusView view;
  view.interlocks = homing::interlock::limit_active;
  view.axes[0].limit_min = true;
  view.axes[0].limit_max = true;
  view.axes[1].limit_min = true;  // one switch: jog away from it, as the interlock says
  const std::string out = homingctl::render_status(view, settings, false);
  CHECK_THAT(out, Catch::Contains("X: both limit switches read active: no direction is away from them"));
  CHECK_THAT(out, Catch::Contains("check the wiring (a broken wire to normally-closed switches) and axis.x.limits_nc"));
  CHECK_THAT(out, !Catch::Contains("Y: both limit switches"));
  CHECK_THAT(out, Catch::Contains("X    switch_release"));
}
