// Several latch passes (docs/health.md): a re-approach method approaches its
// switch edge latch_passes times in one cycle, takes the median as the
// reference and publishes the spread and sigma of the passes.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "homing/health.hpp"
#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

namespace {

// The carriage positions of the last n trigger edges the simulated switch made.
std::vector<double> last_triggers_mm(Rig& r, std::size_t a, std::size_t n) {
  std::vector<double> out;
  for (const auto& e : r.sim().edges(a))
    if (e.to_active) out.push_back(e.actual_mm);
  REQUIRE(out.size() >= n);
  return {out.end() - static_cast<std::ptrdiff_t>(n), out.end()};
}

}  // namespace

SCENARIO("edge statistics: median, spread and standard deviation of the passes", "[health]") {
  const double odd[] = {0.3, 0.1, 0.2};
  const EdgeStats a = edge_stats(odd);
  CHECK(a.median_mm == Approx(0.2));
  CHECK(a.spread_mm == Approx(0.2));
  CHECK(a.sigma_mm == Approx(std::sqrt(0.02 / 3)));
  const double even[] = {1.0, 4.0, 2.0, 3.0};
  const EdgeStats b = edge_stats(even);
  CHECK(b.median_mm == Approx(2.5));
  CHECK(b.spread_mm == Approx(3.0));
  const double one[] = {7.25};
  const EdgeStats c = edge_stats(one);
  CHECK(c.median_mm == 7.25);
  CHECK(c.spread_mm == 0);
  CHECK(c.sigma_mm == 0);
  CHECK(latch_passes_of(0) == 1);
  CHECK(latch_passes_of(kMaxLatchPasses + 3) == kMaxLatchPasses);
}

SCENARIO("five latch passes on a noisy switch: the reference is their median, the spread and sigma are "
         "published", "[health]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.mode = HomingMode::switch_reapproach;
  s.latch_passes = 5;
  s.max_latch_spread_mm = 1;
  r.machine.axes[0].noise_mm = 0.01;
  r.machine.seed = 7;
  REQUIRE(r.home_all());
  const auto passes = last_triggers_mm(r, 0, 5);
  const EdgeStats truth = edge_stats(passes);
  const double tol = edge_tolerance_mm(s, r.dt_s);
  const AxisStatus& x = r.axis(0);
  CHECK(x.homed);
  CHECK(x.health.latch_passes == 5);
  CHECK(truth.spread_mm > 0.005);  // the noise shows
  CHECK(x.health.latch_spread_mm == Approx(truth.spread_mm).margin(2 * tol));
  CHECK(x.health.latch_sigma_mm == Approx(truth.sigma_mm).margin(2 * tol));
  CHECK(r.actual(0) == Approx(rest_point_mm(s, truth.median_mm)).margin(tol));
  CHECK(x.position_mm == Approx(true_position_mm(r, 0, rest_point_mm(s, truth.median_mm))).margin(tol));
}

SCENARIO("one latch pass is the single re-approach: the last trigger is the reference and the spread is 0",
         "[health]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.mode = HomingMode::switch_reapproach;
  s.latch_passes = 1;
  s.max_latch_spread_mm = 0;  // with one pass there is nothing to disagree
  r.machine.axes[0].noise_mm = 0.01;
  REQUIRE(r.home_all());
  const double tol = edge_tolerance_mm(s, r.dt_s);
  CHECK(r.actual(0) == Approx(rest_point_mm(s, last_trigger_mm(r, 0))).margin(tol));
  CHECK(r.axis(0).health.latch_passes == 1);
  CHECK(r.axis(0).health.latch_spread_mm == 0);
  CHECK(r.axis(0).health.latch_sigma_mm == 0);
}

SCENARIO("latch passes in a method that does not re-approach change nothing", "[health]") {
  Rig r;
  r.settings.axes[0].latch_passes = 5;
  REQUIRE(r.home_all());
  CHECK(r.axis(0).health.latch_passes == 0);
  CHECK(r.actual(0) == Approx(rest_point_mm(r.settings.axes[0], last_release_mm(r, 0)))
                           .margin(edge_tolerance_mm(r.settings.axes[0], r.dt_s)));
}

SCENARIO("a software-slaved gantry makes its latch passes on both sides", "[health]") {
  Rig r;
  r.settings.axes[0].mode = HomingMode::switch_reapproach;
  r.settings.axes[0].latch_passes = 3;
  r.settings.axes[0].max_latch_spread_mm = 1;
  r.settings.axes[1] = typical_axis();
  r.settings.axes[1].slave_of = 1;
  r.settings.axes[1].slave_mode = SlaveMode::own_output;
  r.settings.axes[1].max_misalignment_mm = 2;
  r.machine.axes[1].actual_position_mm = 100.3;
  r.machine.axes[0].noise_mm = 0.005;
  r.machine.axes[1].noise_mm = 0.005;
  REQUIRE(r.home_all());
  CHECK(r.axis(0).health.latch_passes == 3);
  CHECK(r.axis(1).health.latch_passes == 3);
  CHECK(r.actual(1) - r.actual(0) == Approx(0).margin(0.05));
}
