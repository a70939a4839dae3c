// Switch health measured on every cycle (docs/health.md): hysteresis, the
// seek-versus-latch edge difference and contact chatter, from the edges the
// phases already see.
#include <catch2/catch.hpp>

#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

SCENARIO("a switch with growing hysteresis: each cycle measures the hysteresis written between cycles",
         "[health]") {
  for (HomingMode mode : {HomingMode::switch_reapproach, HomingMode::switch_release}) {
    DYNAMIC_SECTION(mode_name(mode)) {
      Rig r;
      AxisSettings& s = r.settings.axes[0];
      s.mode = mode;
      // The seek's edge is located from the input's timestamp as precisely as the latch's.
      const double tol = 2 * edge_tolerance_mm(s, r.dt_s) + 1e-6;
      for (double hysteresis : {0.05, 0.08, 0.12, 0.2}) {
        sim::AxisConfig c = r.sim().axis_config(0);
        c.hysteresis_mm = hysteresis;
        r.sim().set_axis_config(0, c);
        REQUIRE(r.home_all());
        CHECK(r.axis(0).health.hysteresis_mm == Approx(hysteresis).margin(mode == HomingMode::switch_release ? 0.002 : tol));
      }
    }
  }
}

SCENARIO("seek and latch find the same edge on an input without latency", "[health]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.mode = HomingMode::switch_reapproach;
  REQUIRE(r.home_all());
  // The seek edge interpolated at 20 mm/s: within seek feedrate x period / 10.
  CHECK(r.axis(0).health.seek_latch_mm == Approx(0).margin(0.002 + edge_tolerance_mm(s, r.dt_s)));
}

SCENARIO("seek and latch edges differ by the seek's extra travel when the input reports levels only",
         "[health]") {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.mode = HomingMode::switch_reapproach;
  r.levels_only();  // an edge is only known to lie within its period: placed at its middle
  REQUIRE(r.home_all());
  const double seek_half_period_mm = 20 * r.dt_s / 2;
  CHECK(std::abs(r.axis(0).health.seek_latch_mm) <= seek_half_period_mm + 1e-6);
}

SCENARIO("a chattering contact: transitions swallowed by the debounce time are counted", "[health]") {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    DYNAMIC_SECTION("seed " << seed) {
      Rig r;
      r.machine.seed = seed;
      AxisSettings& s = r.settings.axes[0];
      s.mode = HomingMode::switch_reapproach;
      s.debounce_ms = 5;
      REQUIRE(r.home_all());
      CHECK(r.axis(0).health.chatter_edges == 0);  // a clean contact
      r.machine.axes[0].bounce_ms = 3;
      sim::AxisConfig c = r.sim().axis_config(0);
      c.bounce_ms = 3;
      r.sim().set_axis_config(0, c);
      REQUIRE(r.home_all());
      CHECK(r.axis(0).health.chatter_edges > 0);
      CHECK(r.axis(0).homed);
    }
  }
}

SCENARIO("an index pulse 0.02 pitch from the switch edge is published with its distance and flagged",
         "[health]") {
  struct Case {
    double pulse_after_release_mm;
    bool near;
  };
  // Pitch 5 mm; the release edge lies at the cam's end plus the hysteresis (0.05 mm).
  for (const Case k : {Case{0.1, true}, Case{2.5, false}, Case{4.9, true}}) {
    DYNAMIC_SECTION("pulse " << k.pulse_after_release_mm << " mm after the release") {
      Rig r;
      AxisSettings& s = r.settings.axes[0];
      s.mode = HomingMode::switch_index;
      r.machine.axes[0].index_pitch_mm = s.index_pitch_mm;
      r.machine.axes[0].index_offset_mm = 0.05 + k.pulse_after_release_mm;
      REQUIRE(r.home_all());
      CHECK(r.axis(0).health.index_distance_mm == Approx(k.pulse_after_release_mm).margin(0.002));
      CHECK(r.axis(0).health.index_near_edge == k.near);
    }
  }
}
