// homingctl check on a home cam axis: the phases it estimates (the search out
// to the limit switch and back, the stop on the cam, the latch across it
// when its far edge is the reference), the stop past a limit switch against
// limit_overtravel, and the warnings a machine builder can act on; over
// Modbus, the simulated cam and limit switches are read from the simulator unit.
#include <catch2/catch.hpp>

#include <map>

#include "check.hpp"
#include "homing/motion.hpp"
#include "registers/defaults.hpp"
#include "tools_helpers.hpp"

using namespace tools_test;

namespace {

// X homes negative on a home cam between limit switches: seek 20 mm/s, latch
// 1 mm/s, 500 mm/s², max_seek_travel 300 mm, overtravel 10 mm.
homing::Settings home_cam_x(homing::CamEdge edge) {
  homing::Settings s = registers::default_settings();
  homing::AxisSettings& x = s.axes[0];
  x.mode = homing::HomingMode::home_cam;
  x.direction = homing::Direction::negative;
  x.limits_fitted = true;
  x.limit_overtravel_mm = 10;
  x.cam_edge = edge;
  x.seek_feedrate_mm_per_min = 1200;
  x.latch_feedrate_mm_per_min = 60;
  x.jog_feedrate_mm_per_min = 600;
  x.acceleration_mm_per_s2 = 500;
  x.debounce_ms = 0;
  x.max_seek_travel_mm = 300;
  x.max_stop_distance_mm = 10;
  x.max_backoff_mm = 30;
  return s;
}

std::map<std::string, double> phases_of(const homingctl::AxisCheck& c) {
  std::map<std::string, double> out;
  for (const auto& [name, t] : c.phases) out[name] = t;
  return out;
}

std::array<std::optional<homingctl::TriggerCam>, homing::kAxisCount> cam_at(double min, double max, double lmin,
                                                                            double lmax) {
  std::array<std::optional<homingctl::TriggerCam>, homing::kAxisCount> cams;
  cams[0] = homingctl::TriggerCam{min, max, 0.05, lmin, lmax};
  return cams;
}

}  // namespace

TEST_CASE("homingctl check estimates a home cam's search out to the limit switch and back, its stop and its latch") {
  const homingctl::CheckReport r = homingctl::check_settings(home_cam_x(homing::CamEdge::behind), {});
  REQUIRE(r.ok());
  const homingctl::AxisCheck& x = r.axes[0];
  auto p = phases_of(x);
  INFO(homingctl::render_check(r));
  for (const char* name : {"cam_seek", "limit_reversal", "cam_stop", "cam_latch", "pull_off"}) CHECK(p.count(name) == 1);
  CHECK(p.count("seek") == 0);
  // 300 mm at 20 mm/s each way (15 s and the ramps), braking at the switch in between.
  CHECK(p["cam_seek"] == Approx(300.0 / 20 + 20.0 / 500));
  CHECK(p["limit_reversal"] == Approx(20.0 / 500 + 300.0 / 20 + 20.0 / 500));
  CHECK(x.seek_worst_s == Approx(p["cam_seek"] + p["limit_reversal"]));
  CHECK(p["cam_stop"] == Approx(20.0 / 500));
  // The search both ways is not after the trigger; the rest is.
  CHECK(x.after_trigger_s == Approx(p["cam_stop"] + p["cam_latch"] + p["pull_off"]));
  // Behind: off the cam where it was found, within the stop (0.4 mm) and the latch's own stop.
  CHECK(p["cam_latch"] < 1.5);
  // The stop past a limit switch from the faster of seek and jog feedrate, with a 20 ms period: 0.4 + 0.4 mm.
  CHECK(x.limits);
  CHECK(x.limit_stop_distance_mm == Approx(0.8));
  CHECK(x.limit_overtravel_mm == 10);
  const std::string text = homingctl::render_check(r);
  CHECK_THAT(text, Catch::Contains("limit switches: stop past one 0.800 / overtravel 10 mm"));
  CHECK_THAT(text, Catch::Contains("cam_seek 15.04 s, limit_reversal 15.08 s"));
  const auto j = homingctl::check_json(r);
  CHECK(j["axes"][0]["limit_overtravel"] == 10);
  CHECK(j["axes"][0]["phases"]["limit_reversal"].get<double>() == Approx(15.08));
}

TEST_CASE("homingctl check: a home cam latched toward its far edge crosses the whole cam") {
  // Without the simulator unit the cam's length is not known: the latch may run its whole max_backoff (30 mm at 1 mm/s).
  const auto unknown = homingctl::check_settings(home_cam_x(homing::CamEdge::ahead), {});
  CHECK(phases_of(unknown.axes[0])["cam_latch"] == Approx(30.0 + 1.0 / 500));
  // A 10 mm cam: its length, the stop and the hysteresis at latch feedrate.
  const auto known = homingctl::check_settings(home_cam_x(homing::CamEdge::ahead), cam_at(10, 20, -100, 100));
  const double latch = phases_of(known.axes[0])["cam_latch"];
  CHECK(latch > 10.0);
  CHECK(latch < 11.0);
  CHECK(known.axes[0].warnings.empty());
}

TEST_CASE("homingctl check warns of a home cam outside its limit switches, a search shorter than the travel, "
          "a latch shorter than the cam and little overtravel") {
  homing::Settings s = home_cam_x(homing::CamEdge::ahead);
  auto warned = [&](const homingctl::CheckReport& r, const std::string& what) {
    const auto& w = r.axes[0].warnings;
    return std::any_of(w.begin(), w.end(), [&](const std::string& x) { return x.find(what) != std::string::npos; });
  };
  CHECK(warned(homingctl::check_settings(s, cam_at(150, 160, -100, 100)), "lies outside the limit switches"));
  CHECK(warned(homingctl::check_settings(s, cam_at(10, 20, -200, 200)),
               "max_seek_travel 300 mm is shorter than the travel between the limit switches 400.000 mm"));
  s.axes[0].max_backoff_mm = 8;  // a 10 mm cam
  CHECK(warned(homingctl::check_settings(s, cam_at(10, 20, -100, 100)), "the latch toward its far edge may end on the cam"));
  s.axes[0].limit_overtravel_mm = 0.9;  // accepted (> 0.8), little margin
  const auto r = homingctl::check_settings(s, {});
  CHECK(r.ok());
  CHECK(warned(r, "uses 89% of limit_overtravel 0.9 mm: little margin"));
}

TEST_CASE("homingctl check on a home cam axis reads the simulated cam and limit switches over Modbus") {
  Daemon d;
  REQUIRE(ctl(d, {"set", "sim.x.limit_min=-100", "sim.x.limit_max=100", "sim.x.hard_stop_min=-110",
                  "sim.x.hard_stop_max=110", "sim.x.sensor_min=150", "sim.x.sensor_max=160",
                  "axis.x.limits_fitted=1", "axis.x.mode=home_cam"})
              .code() == 0);
  const auto r = ctl(d, {"check"});
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK_THAT(r.out, Catch::Contains("cam_seek") && Catch::Contains("limit_reversal") && Catch::Contains("cam_latch"));
  CHECK_THAT(r.out, Catch::Contains("limit switches: stop past one"));
  CHECK_THAT(r.out, Catch::Contains("the home cam [150, 160] mm lies outside the limit switches at -100 and 100 mm"));
  const auto j = json_of(ctl(d, {"check", "--json"}));
  CHECK(j["axes"][0]["phases"].contains("limit_reversal"));
  CHECK(j["axes"][0]["limit_stop_distance"].get<double>() > 0);
}

TEST_CASE("homingctl check lists the limit switches in the wiring of any axis that has them fitted") {
  homing::Settings s = home_cam_x(homing::CamEdge::behind);
  s.axes[0].mode = homing::HomingMode::switch_release;  // homes on its switch, stops at its limit switches
  const homingctl::CheckReport r = homingctl::check_settings(s, {});
  INFO(homingctl::render_check(r));
  REQUIRE(r.axes[0].enabled);
  CHECK(r.axes[0].signals == std::vector<std::string>{"step", "home", "limit_min", "limit_max"});
  CHECK(r.axes[1].signals == std::vector<std::string>{"step", "home"});  // Y: none fitted
}
