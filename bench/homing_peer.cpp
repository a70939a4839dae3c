// Our side of the homing comparison with LinuxCNC (bench/linuxcnc/, the
// "Homing beside LinuxCNC" section of BENCHMARKS.md): the engine and the
// simulator home the axis LinuxCNC homes, from the same start positions, and
// print what each homing gave.
//
//   homing_peer --starts FILE --trip MM --hysteresis MM --seek MM_PER_MIN
//               --latch MM_PER_MIN[,MM_PER_MIN...] --accel MM_PER_S2
//               --pull-off MM [--edge-coordinate MM] [--period-us 1000]
//
// For every latch feedrate, both latch edges (switch_release: the release
// edge, latched moving off the switch at latch feedrate, LinuxCNC's latch
// velocity of the opposite sign to the search; switch_reapproach: the trip
// edge, latched on a slow re-approach, LinuxCNC's latch velocity of the same
// sign) and both ways of reading the switch:
//   level       the engine gets only the switch's level each period (the
//               edge timestamps are dropped), as LinuxCNC's motion controller
//               reads joint.N.home-sw-in: it places the edge in the middle of
//               the period it saw the change in;
//   timestamps  the simulator's edge times within the period, as the GPIO
//               backend gives them from the kernel's line events.
// A fresh engine and simulator per setting, the carriage placed at each start
// in turn (Simulator::place: moved by hand, the controller not told, as
// peer_display.py does to LinuxCNC's carriages), one home each.
//
// One line per homing (the statistics are run_benchmarks.py's, the same code
// for both sides):
//   RESULT mode=release latch=60 inputs=level start=12.3 error_mm=... cycle_s=... rest_mm=...
//   FAIL mode=... latch=... inputs=... start=... state=...
// error_mm: the coordinate the engine gives the carriage once homed, less its
// true coordinate: the edge's coordinate (--edge-coordinate, LinuxCNC's
// HOME_OFFSET) plus the carriage's true distance from the true edge; positive
// when the engine puts the carriage further positive than it is. The engine
// gives home_position to where the pull-off ends, so home_position is the
// edge's coordinate plus the pull-off (this axis homes toward negative, so
// its pull-off is positive: LinuxCNC's HOME - HOME_OFFSET). cycle_s:
// machine time from the command to homed. The switch has no noise here: the
// error is the controller's alone.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench_axis.hpp"
#include "homing/engine.hpp"
#include "homing/sim/simulator.hpp"

using namespace homing;

int main(int argc, char** argv) {
  CLI::App app{"homing_peer: the engine homing LinuxCNC's benchmark axis"};
  std::string starts_file;
  double trip_mm = 0, hysteresis_mm = 0, seek = 0, accel = 0, pull_off = 0, edge_coordinate = 0;
  std::vector<double> latches;
  int period_us = 1000;
  app.add_option("--starts", starts_file, "file of start positions (mm), one a line")->required();
  app.add_option("--trip", trip_mm, "where the switch trips, approached from above (mm)")->required();
  app.add_option("--hysteresis", hysteresis_mm, "travel past the trip edge before it releases (mm)")->required();
  app.add_option("--seek", seek, "seek feedrate (mm/min)")->required();
  app.add_option("--latch", latches, "latch feedrates (mm/min)")->required()->delimiter(',');
  app.add_option("--accel", accel, "acceleration (mm/s^2)")->required();
  app.add_option("--pull-off", pull_off, "pull-off from the reference edge (mm)")->required();
  app.add_option("--edge-coordinate", edge_coordinate, "the coordinate homing gives the reference edge (mm)");
  app.add_option("--period-us", period_us, "control period (us)");
  CLI11_PARSE(app, argc, argv);

  std::vector<double> starts;
  {
    std::ifstream f(starts_file);
    for (double x; f >> x;) starts.push_back(x);
  }
  if (starts.empty()) {
    std::fprintf(stderr, "homing_peer: no start positions in %s\n", starts_file.c_str());
    return 2;
  }
  const double dt_s = period_us * 1e-6;
  std::printf("homing_peer: %zu starts, trip %.6g mm, hysteresis %.6g mm, seek %.6g mm/min, accel %.6g mm/s^2, "
              "pull-off %.6g mm, period %.3f ms\n",
              starts.size(), trip_mm, hysteresis_mm, seek, accel, pull_off, dt_s * 1000);

  long failed = 0;
  for (double latch : latches) {
    for (HomingMode mode : {HomingMode::switch_release, HomingMode::switch_reapproach}) {
      for (bool timestamps : {false, true}) {
        Settings settings;
        AxisSettings& s = settings.axes[0];
        s = bench::switch_axis();
        s.mode = mode;
        s.seek_feedrate_mm_per_min = seek;
        s.latch_feedrate_mm_per_min = latch;
        s.acceleration_mm_per_s2 = accel;
        s.pull_off_mm = pull_off;
        s.home_position_mm = edge_coordinate + pull_off;
        settings.global.sequence_steps = {axis_bit(0), 0, 0, 0, 0, 0};

        // The switch of LinuxCNC's sim_home_switch: active at and below the
        // trip position, released hysteresis above it; no noise, no bounce.
        sim::MachineConfig machine;
        sim::AxisConfig& c = machine.axes[0];
        c.actual_position_mm = starts.front();
        c.sensor_min_mm = trip_mm - 1000;
        c.sensor_max_mm = trip_mm;
        c.hysteresis_mm = hysteresis_mm;
        c.hard_stop_min_mm = trip_mm - 5;
        c.hard_stop_max_mm = trip_mm + 1000;

        Engine engine;
        sim::Simulator simulator(machine);
        auto step = [&](const Commands& cmd) {
          Inputs in = simulator.inputs();
          if (!timestamps)
            for (AxisInputs& a : in.axes) a.sensor_edges = InputEdges{};
          in.commands = cmd;
          const StepResult r = engine.step(settings, in, dt_s);
          simulator.advance(r.outputs, dt_s);
        };
        const bool release = mode == HomingMode::switch_release;
        const double edge_mm = release ? trip_mm + hysteresis_mm : trip_mm;
        const char* mode_text = release ? "release" : "reapproach";
        const char* inputs_text = timestamps ? "timestamps" : "level";

        step(Commands{});
        for (double start : starts) {
          const bench::HomeRun run = bench::home_from(engine, simulator, step, start);
          const double t = run.cycle_s;
          if (!run.homed) {
            ++failed;
            std::printf("FAIL mode=%s latch=%.6g inputs=%s start=%.17g state=%s\n", mode_text, latch, inputs_text,
                        start, std::string(name_of(run.state)).c_str());
            continue;
          }
          const double rest = simulator.actual_position_mm(0);
          const double error = engine.status().axes[0].position_mm - (edge_coordinate + rest - edge_mm);
          std::printf("RESULT mode=%s latch=%.6g inputs=%s start=%.17g error_mm=%.17g cycle_s=%.17g rest_mm=%.17g\n",
                      mode_text, latch, inputs_text, start, error, t, rest);
        }
      }
    }
  }
  return failed == 0 ? 0 : 1;
}
