// Gantry topologies: hardware-slaved (one axis, pushing), software-slaved
// squaring (slave_of, slave_mode 0) and an external commutator (slave_mode 1).
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "accel_watch.hpp"
#include "homing/settings_check.hpp"
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

SCENARIO("a software-slaved gantry starting on a sensor shows its own clearing phase before the seek", "[gantry]") {
  // The slave starts on its cam (which spans [-1000, 0]), the master just off
  // its own: 1.3 mm of skew, within max_misalignment (2 mm).
  Rig r = software_gantry(-0.5);
  r.machine.axes[0].actual_position_mm = 0.8;
  r.step();
  REQUIRE(r.axis(1).sensor);
  std::vector<Phase> master_phases;
  r.on_period = [&](Rig& rig) {
    const Phase p = rig.axis(0).phase;
    if (master_phases.empty() || master_phases.back() != p) master_phases.push_back(p);
  };
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK(r.saw(0, Phase::clear_sensors));
  CHECK(r.saw(1, Phase::clear_sensors));
  CHECK_FALSE(r.saw(0, Phase::pre_move));  // pre_move_mode none: the clearing is not a pre-move
  // Clearing comes first, then the seek.
  const auto clearing = std::find(master_phases.begin(), master_phases.end(), Phase::clear_sensors);
  const auto seek = std::find(master_phases.begin(), master_phases.end(), Phase::seek);
  REQUIRE(clearing != master_phases.end());
  REQUIRE(seek != master_phases.end());
  CHECK(clearing < seek);
  CHECK(r.axis(0).position_mm == Approx(0).margin(1e-9));
  CHECK(r.axis(1).position_mm == Approx(0).margin(1e-9));
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

SCENARIO("external commutator: a slave switch still bouncing when the commutator takes it over keeps its true edge",
         "[gantry][bounce]") {
  // Campaign seed 8001884: the slave rode off its own edge with its master a
  // moment before the commutator switched; the input, taken over mid-bounce,
  // was taken at a bounce's level and the slave squared on a bounce, not on
  // its edge. The master homes on an index pulse whose place is swept so
  // that the commutator switches before, during and after the slave's bounce.
  for (int k = 0; k < 200; ++k) {
    const double index_at = 0.20 + 0.0005 * k;  // master carriage, just past its release at 0.05
    DYNAMIC_SECTION("master's index at " << index_at) {
      Rig r = commutator_gantry(99.8);  // the slave trails by 0.2: it releases during the index search
      r.settings.axes[0].mode = HomingMode::switch_index;
      r.settings.axes[0].index_pitch_mm = 5;
      r.machine.axes[0].index_pitch_mm = 5;
      r.machine.axes[0].index_offset_mm = index_at;
      r.settings.axes[1].debounce_ms = 4;
      r.machine.axes[1].bounce_ms = 3;
      r.machine.seed = static_cast<std::uint64_t>(k);  // a different bounce each time
      REQUIRE(r.home_all());
      const double tol = edge_tolerance_mm(r.settings.axes[0], r.dt_s);
      // Each side at the master's pull-off from its own reference: the
      // master's index, the slave's release edge (0.05 past its cam).
      CHECK(r.actual(0) == Approx(index_at + 1).margin(tol));
      CHECK(r.actual(1) == Approx(1.05).margin(tol));
    }
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

SCENARIO("a software-slaved slave whose sensor is stuck active is the side the not_released alarm names",
         "[gantry][alarms]") {
  Rig r = software_gantry(100);
  r.machine.axes[1].fault = sim::Fault::sensor_stuck_active;
  r.home_all();
  CHECK(r.axis(1).alarm.code == AlarmCode::not_released);
  CHECK(r.axis(1).alarm.phase == Phase::clear_sensors);
  CHECK_FALSE(r.axis(0).alarm);  // the master's sensor released: it is not the one to check
  CHECK(r.status().first_alarm_axis == 1);
}

SCENARIO("a gantry master accelerates at the pair's lower acceleration while homing", "[gantry][safety]") {
  // The slave's drive can do 200 mm/s², the master's 500: every velocity
  // change of either side in the cycle (the ramps of seek, back-off and
  // pull-off, the stop after the trigger) stays within 200 mm/s².
  for (const bool commutator : {false, true}) {
    DYNAMIC_SECTION((commutator ? "external commutator" : "software-slaved")) {
      Rig r = commutator ? commutator_gantry(100.8) : software_gantry(100.8);
      r.settings.axes[1].acceleration_mm_per_s2 = 200;
      REQUIRE_FALSE(check_axis(r.settings, 1));
      AccelWatch acc;
      acc.start(r);
      acc.accel[0] = acc.accel[1] = 200;  // from the configuration, not from the engine's motion_settings
      REQUIRE(r.home_all());
      INFO(acc.describe(0) << "\n" << acc.describe(1));
      CHECK(acc.worst_ratio[0] > 0.5);  // it did ramp, at the pair's rate
      CHECK(acc.within(0));
      CHECK(acc.within(1));
      CHECK(r.actual(0) == Approx(1.05).margin(1e-3));
      CHECK(r.actual(1) == Approx(1.05).margin(1e-3));
    }
  }
}

SCENARIO("a locked slave follows its master's jog and move within its own acceleration", "[gantry][safety]") {
  // The master's drive could ramp at 500 mm/s²; the slave's can do 200.
  for (const bool commutator : {false, true}) {
    DYNAMIC_SECTION((commutator ? "external commutator" : "software-slaved")) {
      Rig r = commutator ? commutator_gantry(100.8) : software_gantry(100.8);
      r.settings.axes[1].acceleration_mm_per_s2 = 200;
      r.settings.axes[0].jog_feedrate_mm_per_min = 1200;  // 20 mm/s: 1 mm to stop at 200 mm/s²
      REQUIRE_FALSE(check_axis(r.settings, 1));
      REQUIRE(r.home_all());
      const double rel0 = r.actual(1) - r.actual(0);
      AccelWatch acc;
      acc.start(r);
      acc.accel[1] = 200;  // the slave's own, from the configuration
      r.jog(0, +1);
      r.run_for(0.5);
      r.release_jogs();
      r.run_until([&] { return !r.any_moving(); }, 5);
      r.move(0, 3);
      r.run_until([&] { return !r.any_moving() && r.axis(0).phase == Phase::idle; }, 10);
      INFO(acc.describe(1));
      CHECK(acc.worst_ratio[1] > 0.5);  // it did ramp, at the pair's rate
      CHECK(acc.within(1));
      CHECK(r.axis(0).position_mm == Approx(3).margin(1e-9));
      CHECK(r.actual(1) - r.actual(0) == Approx(rel0).margin(1e-9));
    }
  }
}

SCENARIO("external commutator: the slave's sensor is read with its own polarity", "[gantry][polarity]") {
  // One NC switch and one NO switch on the pair: while the commutator puts
  // the slave's switch on the master's input, that input means the slave's.
  for (const bool slave_nc : {true, false}) {
    DYNAMIC_SECTION((slave_nc ? "slave NC, master NO" : "slave NO, master NC")) {
      Rig r = commutator_gantry(100.8);
      const std::size_t nc_axis = slave_nc ? 1 : 0;
      r.settings.axes[nc_axis].sensor_nc = true;
      r.machine.axes[nc_axis].sensor_nc = true;
      const double rel0 = r.actual(1) - r.actual(0);
      double worst_rack = 0;
      r.on_period = [&](Rig& rr) { worst_rack = std::max(worst_rack, std::abs(rr.actual(1) - rr.actual(0) - rel0)); };
      const bool homed = r.home_all();
      INFO("X alarm " << alarm_name(r.axis(0).alarm.code) << ", Y alarm " << alarm_name(r.axis(1).alarm.code)
                      << ", worst rack " << worst_rack << " mm");
      REQUIRE(homed);
      const double tol = edge_tolerance_mm(r.settings.axes[0], r.dt_s);
      CHECK(r.saw(1, Phase::align_slave));
      CHECK(last_release_mm(r, 1) == Approx(0.05).margin(1e-9));
      CHECK(r.actual(0) == Approx(1.05).margin(tol));
      CHECK(r.actual(1) == Approx(1.05).margin(tol));  // square
      CHECK(worst_rack <= r.settings.axes[1].max_misalignment_mm);
      CHECK(r.axis(1).homed);
    }
  }
}

SCENARIO("a gantry publishes its skew on the slave: the slave's edge minus the master's, from where each stood",
         "[gantry][health]") {
  struct Case {
    const char* topology;
    bool commutator;
    double slave_start_mm;
    double slave_sensor_max_mm;
    double skew_mm;
  };
  // The master's edge lies at 0.05 (cam end plus hysteresis); both carriages start at 100.
  for (const Case k : {Case{"software", false, 100, 0.4, 0.4}, Case{"software", false, 101.5, 0, -1.5},
                       Case{"commutator", true, 100, 0.4, 0.4}, Case{"commutator", true, 100.8, 0, -0.8}}) {
    DYNAMIC_SECTION(k.topology << " slave at " << k.slave_start_mm << ", its sensor " << k.slave_sensor_max_mm) {
      Rig r = k.commutator ? commutator_gantry(k.slave_start_mm, 0.3) : software_gantry(k.slave_start_mm, 0.3);
      r.machine.axes[1].sensor_max_mm = k.slave_sensor_max_mm;
      REQUIRE(r.home_all());
      const double tol = 2 * edge_tolerance_mm(r.settings.axes[0], r.dt_s) + 1e-6;
      THEN("the slave holds the skew before its switch compensation (0.3 mm) is applied, the master none") {
        CHECK(r.axis(1).health.gantry_skew_measured);
        CHECK(r.axis(1).health.gantry_skew_mm == Approx(k.skew_mm).margin(tol));
        CHECK_FALSE(r.axis(0).health.gantry_skew_measured);
        CHECK(r.axis(0).health.gantry_skew_mm == 0);
      }
      WHEN("the pair homes again from where it was squared") {
        REQUIRE(r.home_all());
        THEN("it stood square with its sensors but for the compensation: the slave rests 0.3 mm further off") {
          CHECK(r.axis(1).health.gantry_skew_measured);
          CHECK(r.axis(1).health.gantry_skew_mm == Approx(-0.3).margin(tol));
        }
      }
    }
  }
}

SCENARIO("an axis that is no gantry slave measures no skew", "[gantry][health]") {
  Rig r;
  REQUIRE(r.home_all());
  for (std::size_t a = 0; a < kAxisCount; ++a) CHECK_FALSE(r.axis(a).health.gantry_skew_measured);
}

namespace {

// Slave - master carriage positions: where the pair stands against square
// (both rigs start their carriages at 100, so square is 0 until homed).
double rack_mm(Rig& r) { return r.actual(1) - r.actual(0); }

// Runs home-all and records the largest rack from `square_mm` on the way.
bool home_all_watching(Rig& r, double square_mm, double& worst_mm) {
  worst_mm = 0;
  r.on_period = [&](Rig& rr) { worst_mm = std::max(worst_mm, std::abs(rack_mm(rr) - square_mm)); };
  const bool homed = r.home_all();
  r.on_period = nullptr;
  return homed;
}

// A software-slaved pair's turns, watched period by period: a side that
// starts a back-off, re-approach or pull-off while the other does not start
// it too from rest; the largest rack; the master's back-offs.
struct TurnWatch {
  int apart_starts = 0;
  int master_back_offs = 0;
  double worst_rack_mm = 0;
};

std::shared_ptr<TurnWatch> watch_turns(Rig& r, std::size_t master) {
  auto w = std::make_shared<TurnWatch>();
  r.on_period = [w, master, before = std::array<Phase, 2>{Phase::idle, Phase::idle}](Rig& rr) mutable {
    w->worst_rack_mm = std::max(w->worst_rack_mm, std::abs(rack_mm(rr)));
    for (std::size_t a : {0, 1}) {
      const Phase now = rr.axis(a).phase;
      const bool turns = now == Phase::back_off || now == Phase::reapproach || now == Phase::pull_off;
      if (!turns || now == before[a]) continue;
      if (a == master && now == Phase::back_off) ++w->master_back_offs;
      if (rr.axis(1 - a).phase != now || rr.axis(1 - a).velocity_mm_per_s != 0) ++w->apart_starts;
    }
    before = {rr.axis(0).phase, rr.axis(1).phase};
  };
  return w;
}

}  // namespace

SCENARIO("a slow software-slaved gantry hands over from one phase to the next with both sides at rest",
         "[gantry]") {
  // 20 mm/s² and 4 mm/s at latch feedrate: a side takes 200 ms and 0.4 mm
  // to stop. The slave's release edge comes 0.5 mm before the master's.
  // Before, the side first at its edge stopped, and the other ran straight
  // on into its pull-off while the first still braked, then started from
  // rest (campaign seed 195009253): the pair racked by more than its edges
  // lie apart. Now each side comes to rest at its edge, and both start the
  // next phase in the same period.
  for (const HomingMode mode : {HomingMode::switch_release, HomingMode::switch_reapproach}) {
    DYNAMIC_SECTION(mode_row(mode).name) {
      Rig r = software_gantry(100);
      for (std::size_t a : {0, 1}) {
        r.settings.axes[a].mode = mode;
        r.settings.axes[a].acceleration_mm_per_s2 = 20;
        r.settings.axes[a].latch_feedrate_mm_per_min = 240;
        r.settings.axes[a].seek_feedrate_mm_per_min = 360;
        r.settings.axes[a].jog_feedrate_mm_per_min = 360;
      }
      r.settings.axes[1].max_misalignment_mm = 1.0;
      r.machine.axes[0].hysteresis_mm = 0.55;
      const auto turns = watch_turns(r, 0);
      const bool homed = r.home_all();
      INFO("alarm on X: " << alarm_name(r.axis(0).alarm.code) << ", on Y: " << alarm_name(r.axis(1).alarm.code));
      REQUIRE(homed);
      CHECK(turns->apart_starts == 0);
      CHECK_FALSE(r.status().alarm);
      // No more than the two release edges lie apart.
      CHECK(turns->worst_rack_mm <= 0.5 + 1e-3);
    }
  }
}

SCENARIO("a slow software-slaved gantry with several latch passes turns at every edge with both sides at rest",
         "[gantry]") {
  // As above, with three slow approaches: each pass backs off to the release
  // and approaches the trigger again. Before, a side took its first pass's
  // release for the partner's and turned back alone in later passes, and
  // left each trigger edge before the last without waiting at all. The
  // engine steps the axes in order: the slave stepped after its master or
  // before it (campaign seed 7400000045: the side stepped first arriving
  // last, its partner turned in that period and it a period later).
  for (const bool slave_first : {false, true}) {
    DYNAMIC_SECTION((slave_first ? "slave stepped before its master" : "slave stepped after its master")) {
      Rig r = software_gantry(100);
      if (slave_first) {
        std::swap(r.settings.axes[0], r.settings.axes[1]);
        std::swap(r.machine.axes[0], r.machine.axes[1]);
        r.settings.axes[0].slave_of = 2;
        r.settings.global.sequence_steps[0] = axis_bit(1);  // the master's step
        r.machine.axes[0].sensor_max_mm = -0.3;             // the slave meets its sensor last
      }
      const std::size_t master = slave_first ? 1 : 0, slave = 1 - master;
      for (std::size_t a : {0, 1}) {
        r.settings.axes[a].mode = HomingMode::switch_reapproach;
        r.settings.axes[a].latch_passes = 3;
        r.settings.axes[a].max_latch_spread_mm = 0.5;
        r.settings.axes[a].acceleration_mm_per_s2 = 20;
        r.settings.axes[a].latch_feedrate_mm_per_min = 240;
        r.settings.axes[a].seek_feedrate_mm_per_min = 360;
        r.settings.axes[a].jog_feedrate_mm_per_min = 360;
      }
      r.settings.axes[slave].max_misalignment_mm = 1.0;
      r.machine.axes[master].hysteresis_mm = 0.55;
      const auto turns = watch_turns(r, master);
      const bool homed = r.home_all();
      INFO("alarm on X: " << alarm_name(r.axis(0).alarm.code) << ", on Y: " << alarm_name(r.axis(1).alarm.code));
      REQUIRE(homed);
      CHECK(turns->master_back_offs == 3);
      CHECK(turns->apart_starts == 0);
      CHECK(r.axis(0).health.latch_passes == 3);
      CHECK(r.axis(1).health.latch_passes == 3);
      // No more than corresponding edges lie apart: the release edges, 0.5 mm
      // (0.8 mm with the slave's sensor 0.3 mm further).
      CHECK(turns->worst_rack_mm <= (slave_first ? 0.8 : 0.5) + 1e-3);
    }
  }
}

SCENARIO("a gantry an alarm left racked squares back on the next home, never further than the limit from square",
         "[gantry][recovery]") {
  for (const bool commutator : {false, true}) {
    DYNAMIC_SECTION((commutator ? "external commutator" : "software-slaved")) {
      Rig r = commutator ? commutator_gantry(100) : software_gantry(100);
      const double limit = r.settings.axes[1].max_misalignment_mm;
      r.set_fault(1, sim::Fault::wire_break);
      double worst = 0;
      REQUIRE_FALSE(home_all_watching(r, 0, worst));
      const Alarm first = r.axis(1).alarm;
      REQUIRE(first.code == AlarmCode::misalignment);
      THEN("the alarm names the slave, which did not find its sensor, in a pair that started square") {
        CHECK(first.side == GantrySide::slave_no_sensor);
        CHECK(first.rack_at_start_mm == Approx(0).margin(1e-9));
        const std::string text = describe_alarm(1, first, r.settings);
        INFO(text);
        CHECK_THAT(text, Catch::Contains("Y (slave) did not find its home sensor") &&
                             Catch::Contains("the pair started the cycle square"));
      }
      THEN("it stopped racked by close to its limit, not beyond") {
        CHECK(worst <= limit + 1e-6);
        CHECK(std::abs(rack_mm(r)) > 0.5 * limit);
      }
      WHEN("the wire is mended and the alarm reset, one home-all squares it") {
        const double racked = rack_mm(r);
        r.set_fault(1, sim::Fault::none);
        r.reset_alarm();
        r.step();
        REQUIRE_FALSE(r.status().alarm);
        REQUIRE(home_all_watching(r, 0, worst));
        const double tol = edge_tolerance_mm(r.settings.axes[0], r.dt_s);
        CHECK(std::abs(racked) > 0.5 * limit);
        CHECK(worst <= limit + 1e-6);
        CHECK(r.actual(0) == Approx(1.05).margin(tol));
        CHECK(r.actual(1) == Approx(1.05).margin(tol));
        CHECK(r.axis(1).homed);
      }
      WHEN("the wire stays broken, the next home stops again, naming the same side and the rack it started with") {
        const double racked = rack_mm(r);
        r.reset_alarm();
        r.step();
        REQUIRE_FALSE(home_all_watching(r, 0, worst));
        const Alarm again = r.axis(1).alarm;
        CHECK(again.code == AlarmCode::misalignment);
        CHECK(again.side == GantrySide::slave_no_sensor);
        CHECK(again.rack_at_start_mm == Approx(racked).margin(1e-6));  // the simulator keeps every step
        CHECK(worst <= std::max(limit, std::abs(racked)) + 1e-6);
        CHECK_THAT(describe_alarm(1, again, r.settings),
                   Catch::Contains(fmt::format("the pair started the cycle {:.3f} mm out of square", racked)));
      }
      WHEN("the gantry is unhomed, the module forgets that square and counts from where the pair stands") {
        r.reset_alarm();
        r.step();
        r.pending.unhome_axes = axis_bit(0);
        r.step();
        REQUIRE_FALSE(home_all_watching(r, rack_mm(r), worst));
        CHECK(r.axis(1).alarm.code == AlarmCode::misalignment);
        CHECK(r.axis(1).alarm.rack_at_start_mm == Approx(0).margin(1e-9));
      }
    }
  }
}

SCENARIO("a gantry whose master's sensor is dead names the master", "[gantry][recovery]") {
  Rig r = software_gantry(100);
  r.set_fault(0, sim::Fault::sensor_stuck_inactive);
  r.home_all();
  const Alarm a = r.axis(1).alarm;
  REQUIRE(a.code == AlarmCode::misalignment);
  CHECK(a.side == GantrySide::master_no_sensor);
  CHECK_THAT(describe_alarm(1, a, r.settings), Catch::Contains("X (master) did not find its home sensor"));
}

SCENARIO("a gantry homed square counts the next cycle's racking from that square, not from where an alarm left it",
         "[gantry][recovery]") {
  // Homed square first; then a dead slave sensor racks it; mended, it squares
  // back to where it was homed.
  Rig r = software_gantry(101.5);  // the slave starts 1.5 mm out: the first cycle squares it
  REQUIRE(r.home_all());
  const double square = rack_mm(r);
  const double limit = r.settings.axes[1].max_misalignment_mm;
  r.set_fault(1, sim::Fault::sensor_stuck_inactive);
  double worst = 0;
  REQUIRE_FALSE(home_all_watching(r, square, worst));
  CHECK(worst <= limit + 1e-6);
  CHECK(r.axis(1).alarm.rack_at_start_mm == Approx(0).margin(1e-6));
  r.set_fault(1, sim::Fault::none);
  r.reset_alarm();
  r.step();
  REQUIRE(home_all_watching(r, square, worst));
  CHECK(worst <= limit + 1e-6);
  CHECK(rack_mm(r) == Approx(square).margin(2 * edge_tolerance_mm(r.settings.axes[0], r.dt_s)));
}

SCENARIO("a gantry an alarm left racked, aborted under return_to_start, goes back to where the cycle found it",
         "[gantry][recovery][failure_policy]") {
  // Campaign seed 20005266: the pair went back to its racked start, which
  // lies at the edge of what square allows; the guard took the arrival for
  // racking and stopped every axis on its way back.
  for (const bool commutator : {false, true}) {
    DYNAMIC_SECTION((commutator ? "external commutator" : "software-slaved")) {
      Rig r = commutator ? commutator_gantry(100) : software_gantry(100);
      r.settings.global.failure_policy = FailurePolicy::return_to_start;
      r.set_fault(1, sim::Fault::wire_break);
      REQUIRE_FALSE(r.home_all());
      REQUIRE(r.axis(1).alarm.code == AlarmCode::misalignment);
      r.set_fault(1, sim::Fault::none);
      // The limit lowered since: the pair now stands beyond it, at the very edge of what it may keep.
      r.settings.axes[1].max_misalignment_mm = 0.9 * std::abs(rack_mm(r));
      r.reset_alarm();
      r.step();
      const double x0 = r.actual(0), y0 = r.actual(1);
      r.pending.home_all = true;
      r.step();
      // Aborted once the pair has squared back on its switches: going back, one side
      // moves alone, fast, toward a place at the edge of what the pair may keep.
      REQUIRE(r.run_until([&] { return std::abs(rack_mm(r) - (y0 - x0)) > 1.5; }, 60));
      REQUIRE(r.status().homing);
      r.dt_s = 0.015;  // long control periods: the guard looks further ahead
      r.pending.abort = true;
      r.step();
      r.run_until([&] { return !r.status().homing && !r.any_moving(); }, 60);
      CHECK(r.axis(1).alarm.code == AlarmCode::aborted);
      CHECK(r.actual(0) == Approx(x0).margin(1e-6));
      CHECK(r.actual(1) == Approx(y0).margin(commutator ? 2.0 : 1e-6));  // a commutator slave rides back with its master
    }
  }
}
