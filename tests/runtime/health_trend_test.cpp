// The health trend's decision alone (server/health_trend.hpp): figures of an
// axis's last cycles in, the warning with its figures out.
#include <catch2/catch.hpp>

#include <vector>

#include "registers/defaults.hpp"
#include "server/health_trend.hpp"
#include "server/monitor.hpp"

using homing::HealthWarning;
using persistence::AxisHealth;
using server::judge_trend;
using server::TrendSettings;

namespace {

// A re-approach axis with 3 latch passes whose switch has this hysteresis.
AxisHealth cycle(double hysteresis_mm) {
  AxisHealth h;
  h.latch_passes = 3;
  h.latch_spread_mm = 0.004;
  h.latch_sigma_mm = 0.002;
  h.hysteresis_mm = hysteresis_mm;
  h.seek_latch_mm = 0.003;
  h.chatter_edges = 1;
  return h;
}

std::vector<AxisHealth> cycles(std::initializer_list<double> hysteresis_mm) {
  std::vector<AxisHealth> out;
  for (double x : hysteresis_mm) out.push_back(cycle(x));
  return out;
}

std::vector<AxisHealth> repeat(const AxisHealth& h, std::size_t n) { return std::vector<AxisHealth>(n, h); }

// 20 cycles, growth 50 %, at least 0.010 mm, skew changes beyond 0.1 mm.
TrendSettings twenty() { return TrendSettings{20, 0.5, 0.010, 0.1}; }

std::vector<HealthWarning> warnings_of(const std::vector<server::TrendVerdict>& vs) {
  std::vector<HealthWarning> out;
  for (const auto& v : vs) out.push_back(v.warning);
  return out;
}

}  // namespace

TEST_CASE("a hysteresis grown from 0.05 to 0.18 mm over the last 20 cycles warns with both figures") {
  auto history = repeat(cycle(0.05), 15);
  for (int i = 0; i < 5; ++i) history.push_back(cycle(0.18));
  const auto verdicts = judge_trend(history, twenty());
  REQUIRE(verdicts.size() == 1);
  CHECK(verdicts[0].warning == HealthWarning::hysteresis_growing);
  CHECK(verdicts[0].now == Approx(0.18));
  CHECK(verdicts[0].was == Approx(0.05));
  CHECK(verdicts[0].cycles == 20);
  const auto settings = registers::default_settings();
  CHECK(server::verdict_text(verdicts[0], settings, 0) ==
        "X hysteresis 0.180 mm, was 0.050 mm over the last 20 cycles: the switch is wearing; check its mounting and "
        "plunger");
}

TEST_CASE("a hysteresis growing a little each cycle warns once it has grown by the growth fraction") {
  std::vector<AxisHealth> history;
  for (int i = 0; i < 20; ++i) history.push_back(cycle(0.05 + 0.004 * i));  // 0.050 ... 0.126 mm
  const auto verdicts = judge_trend(history, twenty());
  REQUIRE(verdicts.size() == 1);
  CHECK(verdicts[0].warning == HealthWarning::hysteresis_growing);
  CHECK(verdicts[0].was == Approx(0.058));  // median of the first 5
  CHECK(verdicts[0].now == Approx(0.118));  // median of the last 5
}

TEST_CASE("a stable switch with noise on its figures gives no warning") {
  const auto history = cycles({0.050, 0.052, 0.049, 0.051, 0.048, 0.053, 0.050, 0.047, 0.052, 0.051,
                               0.049, 0.050, 0.054, 0.048, 0.051, 0.050, 0.052, 0.049, 0.051, 0.050});
  CHECK(judge_trend(history, twenty()).empty());
}

TEST_CASE("fewer cycles than the trend compares give no warning, however the figures grew") {
  auto history = repeat(cycle(0.05), 14);
  for (int i = 0; i < 5; ++i) history.push_back(cycle(0.18));
  REQUIRE(history.size() == 19);
  CHECK(judge_trend(history, twenty()).empty());
  history.push_back(cycle(0.18));
  CHECK(warnings_of(judge_trend(history, twenty())) == std::vector{HealthWarning::hysteresis_growing});
}

TEST_CASE("the trend is off with trend_cycles 0") {
  auto history = repeat(cycle(0.05), 15);
  for (int i = 0; i < 5; ++i) history.push_back(cycle(0.5));
  TrendSettings off = twenty();
  off.cycles = 0;
  CHECK(judge_trend(history, off).empty());
}

TEST_CASE("one wild cycle at the end is no trend: a wear figure must stay grown") {
  auto history = repeat(cycle(0.05), 19);
  history.push_back(cycle(0.4));
  CHECK(judge_trend(history, twenty()).empty());
}

TEST_CASE("growth by the fraction but less than trend_min_change does not warn") {
  auto history = repeat(cycle(0.004), 15);
  for (int i = 0; i < 5; ++i) history.push_back(cycle(0.012));  // +200 %, but 0.008 mm
  CHECK(judge_trend(history, twenty()).empty());
  TrendSettings fine = twenty();
  fine.min_change_mm = 0.005;
  CHECK(warnings_of(judge_trend(history, fine)) == std::vector{HealthWarning::hysteresis_growing});
}

TEST_CASE("a figure that some of the cycles did not measure is not trended") {
  auto history = repeat(cycle(0.05), 15);
  for (int i = 0; i < 5; ++i) history.push_back(cycle(0.18));
  history[3].hysteresis_mm = 0;  // that cycle crossed no release edge
  CHECK(judge_trend(history, twenty()).empty());
}

TEST_CASE("latch spread, seek-latch difference and chatter each warn when they grow") {
  auto grown = [](auto change) {
    auto history = repeat(cycle(0.05), 15);
    for (int i = 0; i < 5; ++i) {
      AxisHealth h = cycle(0.05);
      change(h);
      history.push_back(h);
    }
    return warnings_of(judge_trend(history, twenty()));
  };
  CHECK(grown([](AxisHealth& h) { h.latch_spread_mm = 0.030; }) == std::vector{HealthWarning::latch_spread_growing});
  CHECK(grown([](AxisHealth& h) { h.seek_latch_mm = 0.040; }) == std::vector{HealthWarning::seek_latch_growing});
  CHECK(grown([](AxisHealth& h) { h.seek_latch_mm = -0.040; }) == std::vector{HealthWarning::seek_latch_growing});
  CHECK(grown([](AxisHealth& h) { h.chatter_edges = 6; }) == std::vector{HealthWarning::chatter});
  CHECK(grown([](AxisHealth& h) { h.chatter_edges = 2; }).empty());  // one more edge per cycle is no trend
  // One latch pass has no spread to trend.
  CHECK(grown([](AxisHealth& h) {
          h.latch_passes = 1;
          h.latch_spread_mm = 0.030;
        }).empty());
}

TEST_CASE("chatter text counts edges") {
  const server::TrendVerdict v{HealthWarning::chatter, 6, 1, 20};
  CHECK(server::verdict_text(v, registers::default_settings(), 2) ==
        "Z chatter 6 edges per cycle, was 1 over the last 20 cycles: the contact is wearing out; check the contact, "
        "its connector and noise on the line");
}

TEST_CASE("several growing figures are all reported, the latch spread before the hysteresis") {
  auto history = repeat(cycle(0.05), 15);
  for (int i = 0; i < 5; ++i) {
    AxisHealth h = cycle(0.18);
    h.latch_spread_mm = 0.05;
    history.push_back(h);
  }
  CHECK(warnings_of(judge_trend(history, twenty())) ==
        std::vector{HealthWarning::latch_spread_growing, HealthWarning::hysteresis_growing});
}

TEST_CASE("a gantry slave whose skew jumps beyond max_skew_change warns on that cycle with the pair named") {
  AxisHealth square = cycle(0.05);
  square.gantry_skew_mm = 0.05;
  auto history = repeat(square, 19);
  AxisHealth skewed = square;
  skewed.gantry_skew_mm = 0.42;
  history.push_back(skewed);
  const auto verdicts = judge_trend(history, twenty());
  REQUIRE(verdicts.size() == 1);
  CHECK(verdicts[0].warning == HealthWarning::gantry_skew_changed);
  CHECK(verdicts[0].now == Approx(0.42));
  CHECK(verdicts[0].was == Approx(0.05));
  auto settings = registers::default_settings();
  settings.axes[3].mode = homing::HomingMode::switch_release;
  settings.axes[3].slave_of = 2;  // A is the slave of Y
  CHECK(server::verdict_text(verdicts[0], settings, 3) ==
        "Y/A skew 0.420 mm, was 0.050 mm over the last 20 cycles: check the slave's coupling and sensor");
  SECTION("the next cycle squares the pair on its sensors again: no warning") {
    history.push_back(square);
    CHECK(judge_trend(history, twenty()).empty());
  }
  SECTION("not checked with max_skew_change 0") {
    TrendSettings t = twenty();
    t.max_skew_change_mm = 0;
    CHECK(judge_trend(history, t).empty());
  }
  SECTION("within max_skew_change: no warning") {
    TrendSettings t = twenty();
    t.max_skew_change_mm = 0.5;
    CHECK(judge_trend(history, t).empty());
  }
}

TEST_CASE("a steady skew (a pair homed with a switch compensation) gives no warning") {
  AxisHealth h = cycle(0.05);
  h.gantry_skew_mm = -0.3;
  auto history = repeat(h, 20);
  history[7].gantry_skew_mm = -0.302;
  history[15].gantry_skew_mm = -0.298;
  CHECK(judge_trend(history, twenty()).empty());
}

TEST_CASE("an index pulse near the switch edge warns from its own cycle, first of all") {
  AxisHealth near = cycle(0.05);
  near.index_distance_mm = 0.12;
  near.index_near_edge = true;
  std::vector<AxisHealth> one{near};
  const auto verdicts = judge_trend(one, twenty());
  REQUIRE(verdicts.size() == 1);
  CHECK(verdicts[0].warning == HealthWarning::index_near_edge);
  CHECK(verdicts[0].now == Approx(0.12));
  auto settings = registers::default_settings();
  settings.axes[0].index_pitch_mm = 5;
  CHECK(server::verdict_text(verdicts[0], settings, 0) ==
        "X index pulse 0.120 mm from the switch edge (index_pitch 5 mm): switch noise can home one pitch off; move "
        "the cam or the encoder's index by about half a pitch");
  auto history = repeat(cycle(0.05), 15);
  for (int i = 0; i < 4; ++i) history.push_back(cycle(0.18));
  AxisHealth last = cycle(0.18);
  last.index_near_edge = true;
  history.push_back(last);
  CHECK(warnings_of(judge_trend(history, twenty())) ==
        std::vector{HealthWarning::index_near_edge, HealthWarning::hysteresis_growing});
}

TEST_CASE("the trend settings come from the global trend registers and the axis's max_skew_change") {
  auto settings = registers::default_settings();
  const TrendSettings t = server::trend_settings(settings, 1);
  CHECK(t.cycles == 20);
  CHECK(t.growth_fraction == Approx(0.5));
  CHECK(t.min_change_mm == Approx(0.010));
  CHECK(t.max_skew_change_mm == Approx(0.1));
}

TEST_CASE("the history keeps the health figures of an axis that ended homed, a gantry skew only from a trusted start") {
  homing::AxisStatus axis;
  axis.homed = true;
  axis.homed_at_cycle_start = true;
  axis.health.latch_passes = 3;
  axis.health.hysteresis_mm = 0.08;
  axis.health.chatter_edges = 4;
  axis.health.gantry_skew_measured = true;
  axis.health.gantry_skew_mm = 0.4;
  auto r = server::axis_record(true, axis, 1500);
  REQUIRE(r.health);
  CHECK(r.health->latch_passes == 3);
  CHECK(r.health->hysteresis_mm == 0.08);
  CHECK(r.health->chatter_edges == 4);
  CHECK(r.health->gantry_skew_mm == 0.4);
  axis.homed_at_cycle_start = false;  // the first cycle after a start-up: the pair stood wherever it was left
  r = server::axis_record(true, axis, 1500);
  REQUIRE(r.health);
  CHECK(r.health->hysteresis_mm == 0.08);
  CHECK_FALSE(r.health->gantry_skew_mm);
  axis.homed = false;  // its cycle ended before it found its reference
  CHECK_FALSE(server::axis_record(false, axis, 1500).health);
}
