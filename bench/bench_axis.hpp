#pragma once
// The axis the engine benchmarks home (engine_step_bench, repeatability,
// homing_peer): a switch-and-release home toward negative, 1200 mm/min seek,
// 60 mm/min latch, 500 mm/s^2, within 300 mm; and one home-all of it from a
// given start, as repeatability and homing_peer run it again and again.
#include "homing/engine.hpp"
#include "homing/settings.hpp"
#include "homing/sim/simulator.hpp"

namespace bench {

inline homing::AxisSettings switch_axis() {
  homing::AxisSettings s;
  s.mode = homing::HomingMode::switch_release;
  s.direction = homing::Direction::negative;
  s.seek_feedrate_mm_per_min = 1200;
  s.latch_feedrate_mm_per_min = 60;
  s.acceleration_mm_per_s2 = 500;
  s.max_seek_travel_mm = 300;
  s.max_stop_distance_mm = 10;
  s.max_backoff_mm = 10;
  s.pull_off_mm = 1;
  s.jog_feedrate_mm_per_min = 600;
  return s;
}

struct HomeRun {
  bool homed = false;
  double cycle_s = 0;  // machine time from the command to the cycle's end
  homing::MachineState state = homing::MachineState::not_homed;  // where the cycle ended
};

// Places axis 0's carriage at start_mm, commands a home-all and steps
// (step: one control period with these commands) until the cycle ends, for
// at most 120 s of machine time. A cycle that does not end homed has its
// alarm reset, so the next run starts clean.
template <class Step>
HomeRun home_from(const homing::Engine& engine, homing::sim::Simulator& simulator, Step&& step, double start_mm) {
  simulator.place(0, start_mm);
  step(homing::Commands{});
  homing::Commands home;
  home.home_all = true;
  const double t0 = simulator.time_s();
  step(home);
  while (engine.status().homing && simulator.time_s() - t0 < 120) step(homing::Commands{});
  HomeRun run{engine.status().state == homing::MachineState::homed, simulator.time_s() - t0, engine.status().state};
  if (!run.homed) {
    homing::Commands reset;
    reset.reset_alarm = true;
    step(reset);
  }
  return run;
}

}  // namespace bench
