// How precisely the reference edge is located: interpolated within the period
// from input timestamps, late and random control periods, debounce with
// contact bounce, sensor polarity.
#include <catch2/catch.hpp>

#include <random>

#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

namespace {

// The carriage's rest point implied by the mode's reference edge in the simulator.
double expected_rest(Rig& r, std::size_t a) {
  const AxisSettings& s = r.settings.axes[a];
  const HomingMode m = s.mode;
  if (mode_reapproaches(m)) return rest_point_mm(s, last_trigger_mm(r, a));
  if (m == HomingMode::switch_index) {
    // First index pulse beyond the release edge in the back-off direction (here +).
    const auto& c = r.machine.axes[a];
    const double release = last_release_mm(r, a);
    const double k = std::floor((release - c.index_offset_mm) / c.index_pitch_mm) + 1;
    return rest_point_mm(s, c.index_offset_mm + k * c.index_pitch_mm);
  }
  return rest_point_mm(s, last_release_mm(r, a));
}

}  // namespace

SCENARIO("each mode's reference edge lands where the simulated edge is, within latch × period / 10",
         "[edge]") {
  for (HomingMode mode : {HomingMode::switch_release, HomingMode::switch_reapproach, HomingMode::switch_index,
                          HomingMode::pushing_release, HomingMode::pushing_reapproach}) {
    for (double period : {0.00025, 0.001, 0.004}) {
      for (double latch : {30.0, 60.0, 240.0}) {
        DYNAMIC_SECTION(mode_name(mode) << " period " << period * 1000 << " ms latch " << latch) {
          Rig r;
          r.dt_s = period;
          r.ran_dt_s = period;
          AxisSettings& s = r.settings.axes[0];
          s.mode = mode;
          s.latch_feedrate_mm_per_min = latch;
          s.max_stop_distance_mm = 2;
          r.machine.axes[0].hysteresis_mm = 0.0371;
          r.machine.axes[0].sensor_max_mm = 0.0123;  // edges off any period grid
          r.machine.axes[0].index_pitch_mm = 2.5;
          r.machine.axes[0].index_offset_mm = 0.4321;
          r.machine.axes[0].hard_stop_min_mm = -1.3;
          REQUIRE(r.home_all());
          const double tol = edge_tolerance_mm(s, period);
          const double rest = expected_rest(r, 0);
          CHECK(r.actual(0) == Approx(rest).margin(tol));
          CHECK(r.axis(0).position_mm == Approx(true_position_mm(r, 0, rest)).margin(tol));
          // trigger_position is the reference edge's position in the coordinates believed
          // before (the motor's, on a first homing): the simulator recorded the motor there too.
          if (mode == HomingMode::switch_release) {
            CHECK(r.axis(0).trigger_position_mm == Approx(r.sim().last_edge(0, false)->motor_mm).margin(tol));
          }
        }
      }
    }
  }
}

SCENARIO("without input timestamps the edge is placed mid-period: within latch × period / 2", "[edge]") {
  for (double period : {0.001, 0.003}) {
    DYNAMIC_SECTION("period " << period * 1000 << " ms") {
      Rig r;
      r.dt_s = r.ran_dt_s = period;
      r.levels_only();
      r.machine.axes[0].sensor_max_mm = 0.0123;
      REQUIRE(r.home_all());
      const AxisSettings& s = r.settings.axes[0];
      const double half = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min) * period / 2;
      CHECK(r.actual(0) == Approx(expected_rest(r, 0)).margin(half + 1e-9));
    }
  }
}

SCENARIO("late control periods neither move the reference edge nor lose motion", "[edge][late]") {
  // A shared machine: most periods 1 ms, one in ten several milliseconds late.
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    DYNAMIC_SECTION("seed " << seed) {
      Rig r;
      std::mt19937_64 rng(seed);
      r.next_dt = [&rng] {
        std::uniform_real_distribution<double> u(0, 1);
        return u(rng) < 0.1 ? 0.001 + 0.008 * u(rng) : 0.0005 + 0.001 * u(rng);
      };
      AxisSettings& s = r.settings.axes[0];
      s.mode = seed % 2 ? HomingMode::switch_release : HomingMode::switch_reapproach;
      r.machine.axes[0].sensor_max_mm = 0.0123 * static_cast<double>(seed);
      r.step();
      const double slip0 = r.actual(0) - r.engine.outputs().axes[0].motor.position_mm;
      REQUIRE(r.home_all());
      const double tol = edge_tolerance_mm(s, 0.001);
      const double rest = expected_rest(r, 0);
      CHECK(r.actual(0) == Approx(rest).margin(tol));
      CHECK(r.axis(0).position_mm == Approx(true_position_mm(r, 0, rest)).margin(tol));
      // No motion lost: the carriage is still exactly where the motor's steps put it.
      const double slip = r.actual(0) - r.engine.outputs().axes[0].motor.position_mm;
      CHECK(slip == Approx(slip0).margin(1e-9));
    }
  }
}

SCENARIO("a late period at the seek trigger does not raise stop_distance_exceeded", "[edge][late]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.max_stop_distance_mm = 0.42;  // needed 0.4
  // The period in which the trigger happens (within its first millisecond) is 8 ms long
  // instead of 1: the trigger is seen 7 ms of seek travel later than usual.
  r.next_dt = [&r] {
    const bool trigger_next = r.axis(0).phase == Phase::seek && r.actual(0) > 0 && r.actual(0) - 20 * 0.001 < 0;
    return trigger_next ? 0.008 : 0.001;
  };
  REQUIRE(r.home_all());
  CHECK(r.actual(0) == Approx(1.05).margin(1e-4));
}

SCENARIO("debounce with contact bounce: bounce does not move the located edge", "[edge][debounce]") {
  for (HomingMode mode : {HomingMode::switch_release, HomingMode::switch_reapproach}) {
    for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u}) {
      DYNAMIC_SECTION(mode_name(mode) << " seed " << seed) {
        Rig r;
        r.machine.seed = seed;
        AxisSettings& s = r.settings.axes[0];
        s.mode = mode;
        s.debounce_ms = 5;
        r.machine.axes[0].bounce_ms = 3;  // every bounce gap shorter than the debounce
        REQUIRE(r.home_all());
        const double tol = edge_tolerance_mm(s, r.dt_s);
        CHECK(r.actual(0) == Approx(mode == HomingMode::switch_release ? 1.05 : 1.0).margin(tol));
        CHECK(r.axis(0).position_mm == Approx(0).margin(1e-9));
      }
    }
  }
}

SCENARIO("a normally closed sensor homes exactly like a normally open one", "[edge][polarity]") {
  Rig r;
  r.settings.axes[0].sensor_nc = true;
  r.machine.axes[0].sensor_nc = true;
  r.step();
  CHECK_FALSE(r.axis(0).sensor);  // closed contact = inactive
  CHECK(r.last_inputs.axes[0].sensor_level);
  REQUIRE(r.home_all());
  CHECK(r.actual(0) == Approx(1.05).margin(1e-4));
  WHEN("the polarity setting does not match the wiring") {
    Rig q;
    q.machine.axes[0].sensor_nc = true;  // wired NC, set NO: reads active away from the cam
    q.clear_trace();
    q.home_all(30);
    CHECK(q.status().alarm);
    CHECK(q.axis(0).alarm.code == AlarmCode::not_released);
    CHECK(q.trace[0].path_mm <= q.settings.axes[0].max_backoff_mm + 1e-9);
  }
}

SCENARIO("switch + index: a pulse passing while the release edge is debounced is still the next one",
         "[edge][index]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.mode = HomingMode::switch_index;
  s.debounce_ms = 5;  // 1 mm/s latch: the release is accepted 0.005 mm later
  r.machine.axes[0].index_pitch_mm = 5;
  r.machine.axes[0].index_offset_mm = 0.052;  // 0.002 mm beyond the release edge at 0.05
  REQUIRE(r.home_all());
  CHECK(r.actual(0) == Approx(rest_point_mm(s, 0.052)).margin(edge_tolerance_mm(s, r.dt_s)));
}

SCENARIO("a release during the stop that is still being debounced when the axis comes to rest is an overrun",
         "[edge][stop]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.debounce_ms = 20;  // stop: 0.4 + 20 mm/s · 20 ms = 0.8 mm
  r.machine.axes[0].sensor_min_mm = -0.77;
  r.machine.axes[0].hysteresis_mm = 0;  // releases about 0.03 mm before the halt, accepted after it
  r.home_all(30);
  CHECK(r.axis(0).alarm.code == AlarmCode::overrun_during_stop);
}

SCENARIO("a jog released while braking onto a soft limit after a late period stays inside it",
         "[interlocks][limits][late]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.soft_limits_enable = true;
  s.soft_limit_max_mm = 20;
  REQUIRE(r.home_all());
  r.jog(0, +1);
  // Periods alternate 1 and 3 ms; the jog is released as it brakes onto the limit.
  int n = 0;
  r.next_dt = [&n] { return (++n % 2) ? 0.003 : 0.001; };
  r.run_until([&] { return r.axis(0).position_mm > 19.99; }, 10);
  r.release_jogs();
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK_FALSE(r.status().alarm);
  CHECK(r.axis(0).position_mm <= 20 + 1e-9);
}
