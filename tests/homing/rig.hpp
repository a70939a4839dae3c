#pragma once
// A simulated machine and the engine in lock-step: no sleeping, thousands of
// control periods in milliseconds, exactly repeatable.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

#include "homing/engine.hpp"
#include "homing/sim/simulator.hpp"

namespace rig {

using namespace homing;

// A linear axis that homes toward negative on a switch whose cam spans
// [-1000, 0] mm; the carriage starts at 100 mm. Chosen so that the seek
// stop distance (0.4 mm) fits well inside the cam.
inline AxisSettings typical_axis() {
  AxisSettings s;
  s.mode = HomingMode::switch_release;
  s.direction = Direction::negative;
  s.seek_feedrate_mm_per_min = 1200;   // 20 mm/s
  s.latch_feedrate_mm_per_min = 60;    // 1 mm/s
  s.acceleration_mm_per_s2 = 500;
  s.max_seek_travel_mm = 300;
  s.max_stop_distance_mm = 10;
  s.max_backoff_mm = 10;
  s.pull_off_mm = 1;
  s.home_position_mm = 0;
  s.pre_move_distance_mm = 5;
  s.push_distance_mm = 2;
  s.index_pitch_mm = 5;
  s.max_misalignment_mm = 2;
  s.soft_limit_min_mm = -1;
  s.soft_limit_max_mm = 500;
  s.jog_feedrate_mm_per_min = 600;
  s.stall_timeout_ms = 120'000;  // hard-stop homing: 2 min of pushing at latch feedrate
  s.max_following_error_mm = 0.2;  // hard-stop homing by following error (stall_detect following_error)
  s.drive_home_timeout_s = 30;  // drive mode: the drive's own homing (see typical_sim_axis) takes ~10 s
  s.refcheck_tolerance_mm = 0.1;  // reference check after a restart (homing/trust.hpp)
  return s;
}

inline sim::AxisConfig typical_sim_axis() {
  sim::AxisConfig c;
  c.actual_position_mm = 100;
  c.sensor_min_mm = -1000;
  c.sensor_max_mm = 0;
  c.hysteresis_mm = 0.05;
  c.noise_mm = 0;
  c.hard_stop_min_mm = -5;
  c.hard_stop_max_mm = 1000;
  // Drive mode: the drive homes itself to 0 at 600 mm/min and answers 100 ms later.
  c.drive_home_position_mm = 0;
  c.drive_speed_mm_per_min = 600;
  c.drive_answer_ms = 100;
  return c;
}

struct Rig {
  Settings settings;
  sim::MachineConfig machine;
  Engine engine;
  std::unique_ptr<sim::Simulator> simulator;
  double dt_s = 0.001;
  std::function<double()> next_dt;  // random period lengths, when set
  Commands pending{};  // one-period requests, cleared after each step
  Commands held{};     // levels held every period (jog), merged into each step
  std::optional<LastStops> restore;  // the runtime's record of the last stops, given in the next step only
  double ran_dt_s = 0.001;  // length of the period the simulator last ran
  Inputs last_inputs{};
  std::uint64_t periods = 0;
  std::function<void(Rig&)> on_period;  // invariant checks

  // Only X by default, so a home-all is one axis unless a test adds more.
  Rig() {
    settings.axes[0] = typical_axis();
    settings.global.sequence_steps = {axis_bit(0), 0, 0, 0, 0, 0};
    settings.global.alarm_clears_homed = true;
    for (auto& a : machine.axes) a = typical_sim_axis();
  }

  sim::Simulator& sim() {
    if (!simulator) simulator = std::make_unique<sim::Simulator>(machine);
    return *simulator;
  }
  const Status& status() const { return engine.status(); }
  const AxisStatus& axis(std::size_t a) const { return engine.status().axes[a]; }

  // One control period. The engine is told the length of the period that
  // just ended (the one the simulator ran), then the simulator runs the new
  // commands for the next period, whose length is chosen now. With random
  // periods the two must agree, or motion would be lost between them.
  const Status& step() {
    sim::Simulator& s = sim();
    Inputs in = s.inputs();
    in.commands = pending;
    merge_held(in.commands);
    pending = Commands{};
    in.restore = restore;
    restore.reset();
    tweak_inputs(in);
    last_inputs = in;
    const StepResult r = engine.step(settings, in, ran_dt_s);
    const double dt = next_dt ? next_dt() : dt_s;
    s.advance(r.outputs, dt);
    ran_dt_s = dt;
    ++periods;
    observe();
    if (on_period) on_period(*this);
    return r.status;
  }
  void merge_held(Commands& c) const {
    c.home_all = c.home_all || held.home_all;
    c.home_axes |= held.home_axes;
    c.abort = c.abort || held.abort;
    c.reset_alarm = c.reset_alarm || held.reset_alarm;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (c.jog[a] == 0) c.jog[a] = held.jog[a];
  }
  std::function<void(Inputs&)> tweak_inputs = [](Inputs&) {};

  // Steps until pred is true or max_s of machine time passed; true if pred.
  bool run_until(const std::function<bool()>& pred, double max_s = 120) {
    const double end = sim().time_s() + max_s;
    while (sim().time_s() < end) {
      step();
      if (pred()) return true;
    }
    return false;
  }
  void run_for(double s) {
    const double end = sim().time_s() + s;
    while (sim().time_s() < end) step();
  }

  // Starts home-all and runs it to its end; true if the machine ends homed.
  bool home_all(double max_s = 120) {
    pending.home_all = true;
    step();
    run_until([&] { return !status().homing; }, max_s);
    run_until([&] { return !any_moving(); }, 5);
    return status().state == MachineState::homed;
  }
  bool home_axes(AxisMask mask, double max_s = 120) {
    pending.home_axes = mask;
    step();
    run_until([&] { return !status().homing; }, max_s);
    run_until([&] { return !any_moving(); }, 5);
    return status().alarm == false;
  }
  bool any_moving() const {
    for (const auto& a : engine.status().axes)
      if (a.velocity_mm_per_s != 0) return true;
    return false;
  }
  double actual(std::size_t a) { return sim().actual_position_mm(a); }

  // --- helpers added for the test suite -----------------------------------

  // Jog is a level: held until released.
  void jog(std::size_t a, int dir) { held.jog[a] = static_cast<std::int8_t>(dir); }
  void release_jogs() { held.jog = {}; }
  void reset_alarm() {
    pending.reset_alarm = true;
    step();
  }
  void move(std::size_t a, double target_mm) {
    pending.move_axes = axis_bit(a);
    pending.move_target_mm[a] = target_mm;
    step();
  }
  // Adds axis a as a typical axis homing in sequence step `step` (1..6).
  void add_axis(std::size_t a, int step_no) {
    settings.axes[a] = typical_axis();
    settings.global.sequence_steps[static_cast<std::size_t>(step_no - 1)] |= axis_bit(a);
  }
  // Gives axis a locking indexer (docs/homing-methods.md "Locking indexer"): on in the
  // settings and fitted on the simulated machine, pin out/in after delay_ms.
  void fit_indexer(std::size_t a, double delay_ms = 50, double timeout_ms = 500) {
    settings.axes[a].indexer_lock = true;
    settings.axes[a].lock_timeout_ms = timeout_ms;
    machine.indexer[a] = true;
    machine.axes[a].unlock_delay_ms = delay_ms;
    machine.axes[a].lock_delay_ms = delay_ms;
  }
  // Injects a simulator fault on axis a now.
  void set_fault(std::size_t a, sim::Fault f) {
    sim::AxisConfig c = sim().axis_config(a);
    c.fault = f;
    sim().set_axis_config(a, c);
  }
  // Strips the input timestamps: a backend that reports levels only.
  void levels_only() {
    tweak_inputs = [](Inputs& in) {
      for (auto& a : in.axes) {
        a.sensor_edges = InputEdges{};
      }
    };
  }

  // What happened, period by period, kept cheaply for assertions.
  struct Trace {
    std::uint32_t phases_seen = 0;  // bit per Phase value
    double min_actual = 1e300, max_actual = -1e300;
    double path_mm = 0;            // carriage path length
    std::uint64_t first_move_period = 0, last_move_period = 0;  // 0 = never
    double last_actual = 0;
    bool started = false;
  };
  std::array<Trace, kAxisCount> trace{};
  void clear_trace() {
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      trace[a] = Trace{};
      trace[a].last_actual = actual(a);
      trace[a].started = true;
      trace[a].min_actual = trace[a].max_actual = actual(a);
    }
  }
  bool saw(std::size_t a, Phase p) const { return trace[a].phases_seen & (1u << static_cast<unsigned>(p)); }
  void observe() {
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      Trace& t = trace[a];
      const double x = sim().actual_position_mm(a);
      if (!t.started) {
        t.started = true;
        t.last_actual = x;
      }
      t.phases_seen |= 1u << static_cast<unsigned>(axis(a).phase);
      t.min_actual = std::min(t.min_actual, x);
      t.max_actual = std::max(t.max_actual, x);
      const double d = std::abs(x - t.last_actual);
      t.path_mm += d;
      if (d > 0) {
        if (!t.first_move_period) t.first_move_period = periods;
        t.last_move_period = periods;
      }
      t.last_actual = x;
    }
  }
};

// X homes negative onto a cam over [cam_min, cam_max] in mid-travel, between
// limit switches at -100 and +100 (mechanical stops 10 mm beyond), its
// carriage at start_mm.
inline void fit_home_cam(Rig& r, double start_mm, double cam_min, double cam_max, CamEdge edge = CamEdge::behind) {
  AxisSettings& s = r.settings.axes[0];
  s.mode = HomingMode::home_cam;
  s.limits_fitted = true;
  s.limit_overtravel_mm = 10;
  s.cam_edge = edge;
  s.max_backoff_mm = 30;  // covers the cam's length: the far edge may be the reference
  s.soft_limit_min_mm = -1000;
  sim::AxisConfig& m = r.machine.axes[0];
  m.actual_position_mm = start_mm;
  m.sensor_min_mm = cam_min;
  m.sensor_max_mm = cam_max;
  m.limit_min_mm = -100;
  m.limit_max_mm = 100;
  m.hard_stop_min_mm = -110;
  m.hard_stop_max_mm = 110;
}

}  // namespace rig
