#include <catch2/catch.hpp>

#include "helpers.hpp"

using namespace persistence;

namespace {
HomingRun run_with(std::int64_t start, double x_corr, std::optional<double> y_corr, std::int32_t result = 0) {
  HomingRun r;
  r.start_ms = start;
  r.end_ms = start + 2500;
  r.axes = 0b11;
  r.result = result;
  r.alarm_axis = result ? 1 : -1;
  r.axis[0] = {true, x_corr, 1200};
  r.axis[1] = {true, y_corr, 1800};
  return r;
}
}  // namespace

TEST_CASE("a homing run is recorded with its times, axes, result and per-axis corrections", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  auto id1 = store.record_homing_run(run_with(1000, 0.012, -0.004));
  auto id2 = store.record_homing_run(run_with(9000, 0.015, std::nullopt, 1));
  REQUIRE(id1);
  REQUIRE(id2);
  auto runs = store.recent_runs(10);
  REQUIRE(runs);
  REQUIRE(runs->size() == 2);
  const auto& last = (*runs)[0];
  CHECK(last.id == *id2);
  CHECK(last.start_ms == 9000);
  CHECK(last.end_ms == 11500);
  CHECK(last.axes == 0b11);
  CHECK(last.result == 1);
  CHECK(last.alarm_axis == 1);
  CHECK(last.axis[0].present);
  CHECK(last.axis[0].correction_mm == Approx(0.015));
  CHECK(last.axis[0].duration_ms == 1200);
  CHECK(last.axis[1].present);
  CHECK_FALSE(last.axis[1].correction_mm);
  CHECK_FALSE(last.axis[2].present);
  CHECK((*runs)[1].axis[1].correction_mm == Approx(-0.004));
}

TEST_CASE("the last N home corrections of an axis are summarised", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  // An old outlier that falls outside the window of the last 4.
  REQUIRE(store.record_homing_run(run_with(0, 5.0, 0.0)));
  for (double c : {0.010, 0.020, 0.030, 0.040}) REQUIRE(store.record_homing_run(run_with(1, c, std::nullopt)));
  auto s = store.correction_summary(0, 4);
  REQUIRE(s);
  CHECK(s->count == 4);
  CHECK(s->mean == Approx(0.025));
  CHECK(s->spread == Approx(0.030));
  CHECK(s->min == Approx(0.010));
  CHECK(s->max == Approx(0.040));
  CHECK(s->stddev == Approx(0.0129099).epsilon(1e-4));
  auto y = store.correction_summary(1, 10);  // runs without a Y correction are skipped
  REQUIRE(y);
  CHECK(y->count == 1);
  CHECK(y->stddev == 0);
  CHECK(store.correction_summary(2, 10)->count == 0);
  CHECK_FALSE(store.correction_summary(6, 10));
}

TEST_CASE("the homing history keeps only the newest runs up to its limit", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  auto o = test::options();
  o.history_max_rows = 3;
  auto store = test::open_ok(dir.file("settings.db"), report, o);
  for (int i = 0; i < 10; ++i) REQUIRE(store.record_homing_run(run_with(i * 100, i, i)));
  auto runs = store.recent_runs(100);
  REQUIRE(runs);
  REQUIRE(runs->size() == 3);
  CHECK(runs->front().start_ms == 900);
  CHECK(runs->back().start_ms == 700);
  CHECK(test::sql_int(dir.file("settings.db"), "SELECT count(*) FROM homing_axes") == 6);
}

TEST_CASE("the history survives reopening", "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  { REQUIRE(test::open_ok(dir.file("settings.db"), report).record_homing_run(run_with(42, 0.5, 0.25))); }
  auto store = test::open_ok(dir.file("settings.db"), report);
  auto runs = store.recent_runs(5);
  REQUIRE(runs);
  REQUIRE(runs->size() == 1);
  CHECK(runs->front().axis[1].correction_mm == Approx(0.25));
}

TEST_CASE("an axis recorded as excluded keeps its reason and stays out of the correction statistics",
          "[persistence]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  HomingRun first = run_with(0, 0, 0);
  first.axis[0] = {true, std::nullopt, 1200, Excluded::not_homed_before};
  first.axis[1] = {true, std::nullopt, 1800, Excluded::not_homed_before};
  REQUIRE(store.record_homing_run(first));
  REQUIRE(store.record_homing_run(run_with(1, 0.010, 0.002)));
  HomingRun failed = run_with(2, 0, 0, 3);
  failed.axis[0] = {true, std::nullopt, 1200, Excluded::cycle_failed};
  failed.axis[1] = {true, std::nullopt, 1800, Excluded::cycle_failed};
  REQUIRE(store.record_homing_run(failed));
  // A correction recorded with an exclusion is not counted either.
  HomingRun odd = run_with(3, 84.0, std::nullopt);
  odd.axis[0].excluded = Excluded::not_homed_before;
  REQUIRE(store.record_homing_run(odd));

  auto runs = store.recent_runs(10);
  REQUIRE(runs);
  REQUIRE(runs->size() == 4);
  CHECK((*runs)[3].axis[0].excluded == Excluded::not_homed_before);
  CHECK((*runs)[3].axis[1].excluded == Excluded::not_homed_before);
  CHECK((*runs)[2].axis[0].excluded == Excluded::no);
  CHECK((*runs)[1].axis[0].excluded == Excluded::cycle_failed);
  CHECK(excluded_text(Excluded::not_homed_before) == "not homed before the cycle");
  auto s = store.correction_summary(0, 10);
  REQUIRE(s);
  CHECK(s->count == 1);
  CHECK(s->mean == Approx(0.010));
  CHECK(s->spread == 0);
}

namespace {
AxisHealth figures(double hysteresis_mm, std::optional<double> skew_mm = std::nullopt) {
  AxisHealth h;
  h.latch_passes = 3;
  h.latch_spread_mm = 0.004;
  h.latch_sigma_mm = 0.0015;
  h.hysteresis_mm = hysteresis_mm;
  h.seek_latch_mm = -0.002;
  h.chatter_edges = 2;
  h.index_distance_mm = 0.3;
  h.index_near_edge = true;
  h.gantry_skew_mm = skew_mm;
  return h;
}
}  // namespace

TEST_CASE("the health figures of each homed axis are kept with its run and read back", "[persistence][health]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  HomingRun run = run_with(1000, 0.01, 0.02);
  run.axis[0].health = figures(0.05);
  run.axis[1].health = figures(0.07, 0.42);
  REQUIRE(store.record_homing_run(run));
  auto runs = store.recent_runs(1);
  REQUIRE(runs);
  REQUIRE(runs->size() == 1);
  CHECK(runs->front().axis[0].health == figures(0.05));
  CHECK(runs->front().axis[1].health == figures(0.07, 0.42));
  CHECK_FALSE(runs->front().axis[2].health);
}

TEST_CASE("the health history of an axis holds its last N runs with figures, oldest first", "[persistence][health]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  for (int i = 0; i < 6; ++i) {
    HomingRun run = run_with(1000 * i, 0.01, 0.02);
    if (i != 4) run.axis[0].health = figures(0.05 + 0.01 * i);  // run 4 found no reference: no figures
    run.axis[1].health = figures(0.5, 0.1 * i);
    REQUIRE(store.record_homing_run(run));
  }
  auto x = store.health_history(0, 3);
  REQUIRE(x);
  REQUIRE(x->size() == 3);
  CHECK((*x)[0].health.hysteresis_mm == Approx(0.07));
  CHECK((*x)[1].health.hysteresis_mm == Approx(0.08));  // run 4 is not among them
  CHECK((*x)[2].health.hysteresis_mm == Approx(0.10));
  CHECK((*x)[2].start_ms == 5000);
  CHECK((*x)[0].run_id < (*x)[1].run_id);
  CHECK_FALSE((*x)[2].health.gantry_skew_mm);
  auto y = store.health_history(1, 100);
  REQUIRE(y);
  REQUIRE(y->size() == 6);
  CHECK(y->back().health.gantry_skew_mm == Approx(0.5));
  CHECK(store.health_history(2, 10)->empty());
  CHECK_FALSE(store.health_history(6, 10));
}
