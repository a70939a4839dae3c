// The mode table (homing/modes.hpp) says what each homing method does; these
// tests hold every row to what its phases really do on the simulator: the
// phases shown, the inputs it cannot home without, the outputs it drives and
// the coordinate it gives the axis.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "homing/last_stop.hpp"
#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

namespace {

// A method as one axis has it: its row, and for a method that finds a
// mechanical stop each way of telling the stop (axis.<a>.stall_detect).
struct Variant {
  const ModeRow* row;
  StallDetect detect;
};
std::vector<Variant> variants() {
  std::vector<Variant> out;
  for (const ModeRow& row : kModeTable) {
    out.push_back({&row, StallDetect::stall_input});
    if (row.detects_stop()) out.push_back({&row, StallDetect::following_error});
  }
  return out;
}
std::string variant_name(const Variant& v) {
  std::string name = "mode " + std::string(v.row->name);
  if (v.row->detects_stop()) name += " by " + std::string(name_of(v.detect));
  return name;
}

// X on the typical switch (release edge at 0.05 mm, trigger edge at 0), its
// mechanical stop at -5 mm, an index pulse every 5 mm at 0.3 mm, an absolute
// encoder reading carriage + 7,
// a pre-move and a final move wherever the method allows them.
Rig rig_for(const ModeRow& row, StallDetect detect = StallDetect::stall_input) {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.mode = row.value;
  s.stall_detect = detect;
  s.pre_move_mode = PreMove::always;
  s.final_move_enable = true;
  s.final_position_mm = 5;
  s.home_position_mm = 2;
  r.machine.axes[0].index_pitch_mm = 5;
  r.machine.axes[0].index_offset_mm = 0.3;
  r.machine.axes[0].absolute_offset_mm = 7;
  r.machine.axes[0].actual_position_mm = 40;
  if (row.runs(Phase::limit_reversal)) {
    // Home cam: seeking positive from 40 it meets the limit switch at 60
    // first, reverses, finds the cam below 0 and leaves it upward (cam_edge
    // ahead): the same release at 0.05 and pull-off above it as the others.
    s.limits_fitted = true;
    s.direction = Direction::positive;
    s.cam_edge = CamEdge::ahead;
    s.limit_overtravel_mm = 10;
    r.machine.axes[0].limit_max_mm = 60;
  }
  return r;
}

// The phases the axis showed during its cycle, each once in the order first seen.
struct Watched {
  std::vector<Phase> phases;
  bool push_output = false;
  bool drive_request = false;
};

Watched home_and_watch(Rig& r) {
  Watched w;
  r.on_period = [&](Rig& rig) {
    const Phase p = rig.axis(0).phase;
    const bool homing_phase = p != Phase::idle && p != Phase::waiting && p != Phase::done && p != Phase::stopping;
    if (homing_phase && (w.phases.empty() || w.phases.back() != p)) w.phases.push_back(p);
    w.push_output = w.push_output || rig.engine.outputs().axes[0].push_output;
    w.drive_request = w.drive_request || rig.engine.outputs().axes[0].drive_request;
  };
  r.home_all();
  r.on_period = nullptr;
  return w;
}

// The row's phases that take at least one period: assign is over in the
// period its predecessor ends (it only sets the coordinate).
std::vector<Phase> timed_phases(const ModeRow& row) {
  std::vector<Phase> out;
  for (const Phase p : row.phase_list())
    if (p != Phase::assign) out.push_back(p);
  return out;
}

// The reference edge of a reference-edge method, from the simulated machine:
// the release at 0.05 (cam edge + hysteresis), the trigger at 0 when the
// method re-approaches, the next index pulse (0.3) when it runs the index phase.
double reference_edge_mm(const ModeRow& row) {
  if (row.runs(Phase::index)) return 0.3;
  if (row.runs(Phase::reapproach)) return 0.0;
  return 0.05;
}

}  // namespace

TEST_CASE("every mode shows the phases of its row in order and drives the outputs its row names", "[modes][table]") {
  for (const Variant& v : variants()) {
    const ModeRow& row = *v.row;
    DYNAMIC_SECTION(variant_name(v)) {
      Rig r = rig_for(row, v.detect);
      r.step();
      const Watched w = home_and_watch(r);
      CHECK(r.axis(0).homed);
      CHECK_FALSE(r.status().alarm);
      CHECK(w.phases == timed_phases(row));
      CHECK(w.push_output == row.needs_signal(Signal::push_output));
      CHECK(w.drive_request == row.needs_signal(Signal::drive_request));
    }
  }
}

TEST_CASE("a mode cannot home without an input its row names, and homes without those it does not", "[modes][table]") {
  struct Missing {
    Signal signal;
    const char* what;
    std::function<void(Rig&)> take_away;
  };
  const Missing inputs[] = {
      {Signal::home_sensor, "home sensor", [](Rig& r) { r.machine.axes[0].fault = sim::Fault::sensor_stuck_inactive; }},
      {Signal::index, "index pulse", [](Rig& r) { r.machine.axes[0].index_pitch_mm = 0; }},
      {Signal::absolute_encoder, "absolute encoder",
       [](Rig& r) { r.tweak_inputs = [](Inputs& in) { in.axes[0].absolute_valid = false; }; }},
      {Signal::stall, "stall output", [](Rig& r) { r.machine.axes[0].fault = sim::Fault::stall_dead; }},
      {Signal::limit_max, "limit switches", [](Rig& r) { r.machine.axes[0].fault = sim::Fault::limits_dead; }},
      {Signal::drive_done, "drive's home done",
       [](Rig& r) { r.tweak_inputs = [](Inputs& in) { in.axes[0].drive_done = false; }; }},
  };
  for (const Variant& v : variants()) {
    for (const Missing& m : inputs) {
      DYNAMIC_SECTION(variant_name(v) << " without its " << m.what) {
        Rig r = rig_for(*v.row, v.detect);
        m.take_away(r);
        r.step();
        r.home_all();
        // The row's signals, with the stop detection the axis chose.
        if (needs_signal(r.settings.axes[0], m.signal)) {
          CHECK(r.status().alarm);
          CHECK_FALSE(r.axis(0).homed);
        } else {
          CHECK_FALSE(r.status().alarm);
          CHECK(r.axis(0).homed);
        }
      }
    }
  }
}

TEST_CASE("every mode gives the axis the coordinate its row defines", "[modes][table]") {
  for (const Variant& v : variants()) {
    const ModeRow& row = *v.row;
    DYNAMIC_SECTION(variant_name(v)) {
      Rig r = rig_for(row, v.detect);
      r.step();
      const double start = r.actual(0);
      const double believed_before = r.axis(0).position_mm;
      REQUIRE(r.home_all());
      const AxisSettings& s = r.settings.axes[0];
      // Machine coordinate minus carriage position: where the method put zero.
      const double offset = r.axis(0).position_mm - r.actual(0);
      switch (row.coordinate) {
        case Coordinate::none:
          CHECK(r.actual(0) == start);
          CHECK(r.axis(0).position_mm == believed_before);
          break;
        case Coordinate::here:
          CHECK(offset == Approx(s.home_position_mm - start).margin(1e-9));
          break;
        case Coordinate::absolute_encoder:
          CHECK(offset == Approx(r.machine.axes[0].absolute_offset_mm - s.home_position_mm).margin(1e-9));
          break;
        case Coordinate::drive_reference:
          // home_position where the drive's own homing left the carriage.
          CHECK(offset == Approx(s.home_position_mm - r.machine.axes[0].drive_home_position_mm).margin(1e-9));
          break;
        case Coordinate::reference_edge: {
          // Negative homing: home_position lies pull_off above the reference edge.
          // (A home cam pulls off away from the cam on its reference side, here upward too.)
          const double away = row.runs(Phase::cam_latch) ? (s.cam_edge == CamEdge::ahead) == (s.direction == Direction::positive) ? 1.0 : -1.0 : 0.0;
          const double rest = row.runs(Phase::cam_latch) ? reference_edge_mm(row) + away * s.pull_off_mm
                                                         : rest_point_mm(s, reference_edge_mm(row));
          CHECK(offset == Approx(s.home_position_mm - rest).margin(edge_tolerance_mm(s, r.dt_s)));
          break;
        }
        case Coordinate::mechanical_stop: {
          // Pull-off above the stop the carriage was pushed against, whatever steps it lost there.
          const double rest = rest_point_mm(s, r.machine.axes[0].hard_stop_min_mm);
          CHECK(offset == Approx(s.home_position_mm - rest).margin(1e-9));
          break;
        }
      }
    }
  }
}

TEST_CASE("after a clean stop and a restart, every mode whose row has a switch edge passes the reference check and every other mode is refused it",
          "[modes][table][trust]") {
  for (const Variant& v : variants()) {
    const ModeRow& row = *v.row;
    DYNAMIC_SECTION(variant_name(v)) {
      Rig before = rig_for(row, v.detect);
      before.step();
      REQUIRE(before.home_all());
      const LastStops stops = last_stops_at_shutdown(before.settings, before.status(), before.engine.outputs());
      const double offset = before.axis(0).position_mm - before.actual(0);
      // The same machine started again: the carriage where it was, the last stops given.
      Rig r = rig_for(row, v.detect);
      r.machine.axes[0].actual_position_mm = before.actual(0);
      r.restore = stops;
      r.step();
      const bool homes = mode_homes(row.value);
      CHECK(r.axis(0).trust == (homes ? Trust::last_stop_clean : Trust::unknown));
      r.pending.refcheck_axes = axis_bit(0);
      r.step();
      const CommandResult result = r.status().last_command_result;
      r.run_until([&] { return !r.status().homing && !r.any_moving(); }, 60);
      if (refcheck_edge(row) != RefcheckEdge::none) {
        CHECK(result == CommandResult::accepted);
        CHECK(r.axis(0).trust == Trust::reference_checked);
        CHECK(r.axis(0).homed);
        CHECK(std::abs(r.axis(0).refcheck_error_mm) <= r.settings.axes[0].refcheck_tolerance_mm);
        CHECK(r.actual(0) == Approx(before.actual(0)).margin(1e-9));
        CHECK(r.axis(0).position_mm - r.actual(0) == Approx(offset).margin(r.settings.axes[0].refcheck_tolerance_mm));
      } else {
        CHECK(result == (homes ? CommandResult::refused_no_switch_edge : CommandResult::refused_invalid));
        CHECK(r.actual(0) == before.actual(0));
        CHECK_FALSE(r.status().homing);
      }
    }
  }
}
