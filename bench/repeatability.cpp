// Homing repeatability on the simulated machine.
//
//   homing_repeatability [runs=1000] [noise_mm=0.005] [seed=1]
//
// Homes one simulated axis `runs` times from random start positions with a
// noisy home sensor (every edge position drawn with std deviation noise_mm),
// and prints:
//   - the spread of the carriage's actual position after homing (std dev and
//     max - min) beside the simulated noise std and their ratio: a sound
//     homing adds nothing to the sensor's own noise (ratio close to 1, since
//     the reference is one release edge);
//   - the cycle time (machine time from the command to homed) beside the
//     time-optimal minimum for the same settings, and their ratio.
//
// The time-optimal minimum, from the trapezoidal profiles of each phase
// (v_s seek, v_l latch feedrate, a acceleration, D distance from the start to
// the trigger edge, h the sensor's hysteresis, p the pull-off):
//   ramp(d, v0, v)    time to cover d starting at v0, accelerating at a up to v
//                     and not needing to stop at the end:
//                       d_acc = (v² - v0²) / 2a;  d >= d_acc: (v - v0)/a + (d - d_acc)/v
//                                                  else: (sqrt(v0² + 2ad) - v0)/a
//   seek:     t1 = ramp(D, 0, v_s), reaching v1 = min(v_s, sqrt(2aD)) at the trigger
//   stop:     t2 = v1 / a, over s = v1² / 2a past the trigger
//   back-off: t3 = v_l/a-limited ramp(s + h, 0, v_l) from rest to the release edge
//             (the sensor releases h beyond the trigger edge), arriving at v3
//   pull-off: t4 = the fastest move over p from v3 to rest with peak v_s:
//               d_up = (v_s² - v3²)/2a, d_down = v_s²/2a
//               p >= d_up + d_down: (v_s - v3)/a + v_s/a + (p - d_up - d_down)/v_s
//               else peak vp = sqrt((2ap + v3²)/2): (vp - v3)/a + vp/a
//   minimum = t1 + t2 + t3 + t4
// The engine's real cycle also spends control periods seeing each edge and
// one period on each phase hand-over; the ratio shows what those cost.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "bench_axis.hpp"
#include "homing/engine.hpp"
#include "homing/motion.hpp"
#include "homing/sim/simulator.hpp"

using namespace homing;

namespace {

double ramp_time(double d, double v0, double v, double a) {
  const double d_acc = (v * v - v0 * v0) / (2 * a);
  if (d >= d_acc) return (v - v0) / a + (d - d_acc) / v;
  return (std::sqrt(v0 * v0 + 2 * a * d) - v0) / a;
}

double ramp_speed(double d, double v0, double v, double a) { return std::min(v, std::sqrt(v0 * v0 + 2 * a * d)); }

double minimum_cycle_s(const AxisSettings& s, double distance_to_trigger_mm, double hysteresis_mm) {
  const double vs = mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min);
  const double vl = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
  const double a = s.acceleration_mm_per_s2;
  const double t1 = ramp_time(distance_to_trigger_mm, 0, vs, a);
  const double v1 = ramp_speed(distance_to_trigger_mm, 0, vs, a);
  const double t2 = v1 / a;
  const double back = stop_distance_mm(v1, a) + hysteresis_mm;
  const double t3 = ramp_time(back, 0, vl, a);
  const double v3 = ramp_speed(back, 0, vl, a);
  const double p = s.pull_off_mm;
  const double d_up = (vs * vs - v3 * v3) / (2 * a), d_down = stop_distance_mm(vs, a);
  double t4;
  if (p >= d_up + d_down) {
    t4 = (vs - v3) / a + vs / a + (p - d_up - d_down) / vs;
  } else {
    const double vp = std::sqrt((2 * a * p + v3 * v3) / 2);
    t4 = vp >= v3 ? (vp - v3) / a + vp / a : v3 / a;
  }
  return t1 + t2 + t3 + t4;
}

struct Stats {
  double mean = 0, sd = 0, min = 0, max = 0;
};
Stats stats(const std::vector<double>& v) {
  Stats s;
  if (v.empty()) return s;
  s.min = *std::min_element(v.begin(), v.end());
  s.max = *std::max_element(v.begin(), v.end());
  for (double x : v) s.mean += x;
  s.mean /= static_cast<double>(v.size());
  for (double x : v) s.sd += (x - s.mean) * (x - s.mean);
  s.sd = v.size() > 1 ? std::sqrt(s.sd / static_cast<double>(v.size() - 1)) : 0;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const long runs = argc > 1 ? std::strtol(argv[1], nullptr, 10) : 1000;
  const double noise_mm = argc > 2 ? std::strtod(argv[2], nullptr) : 0.005;
  const unsigned long long seed = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1;
  if (runs < 2 || !(noise_mm >= 0)) {
    std::fprintf(stderr, "usage: %s [runs>=2] [noise_mm>=0] [seed]\n", argv[0]);
    return 2;
  }
  constexpr double dt_s = 0.001;

  Settings settings;
  AxisSettings& s = settings.axes[0];
  s = bench::switch_axis();
  settings.global.sequence_steps = {axis_bit(0), 0, 0, 0, 0, 0};

  sim::MachineConfig machine;
  sim::AxisConfig& c = machine.axes[0];
  c.actual_position_mm = 50;
  c.sensor_min_mm = -1000;
  c.sensor_max_mm = 0;
  c.hysteresis_mm = 0.05;
  c.noise_mm = noise_mm;
  c.hard_stop_min_mm = -5;
  c.hard_stop_max_mm = 1000;
  machine.seed = seed;

  Engine engine;
  sim::Simulator simulator(machine);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> start_mm(5, 100);

  auto step = [&](const Commands& cmd) {
    Inputs in = simulator.inputs();
    in.commands = cmd;
    const StepResult r = engine.step(settings, in, dt_s);
    simulator.advance(r.outputs, dt_s);
  };

  std::vector<double> rest, cycle, minimum;
  long failed = 0;
  step(Commands{});
  for (long i = 0; i < runs; ++i) {
    const double start = start_mm(rng);
    const bench::HomeRun run = bench::home_from(engine, simulator, step, start);
    if (!run.homed) {
      ++failed;
      continue;
    }
    rest.push_back(simulator.actual_position_mm(0));
    cycle.push_back(run.cycle_s);
    // The trigger edge is the cam's end (noise aside) at 0.
    minimum.push_back(minimum_cycle_s(s, start - c.sensor_max_mm, c.hysteresis_mm));
  }

  const Stats r = stats(rest), ct = stats(cycle), mn = stats(minimum);
  std::printf("homing repeatability: %ld runs (%ld failed), mode %s, period %.3f ms, seed %llu\n", runs, failed,
              std::string(mode_name(s.mode)).c_str(), dt_s * 1000, seed);
  std::printf("seek %.0f mm/min, latch %.0f mm/min, accel %.0f mm/s^2, pull-off %.2f mm, hysteresis %.3f mm\n\n",
              s.seek_feedrate_mm_per_min, s.latch_feedrate_mm_per_min, s.acceleration_mm_per_s2, s.pull_off_mm,
              c.hysteresis_mm);
  std::printf("%-34s %12s %12s %12s\n", "position after homing", "measured", "sensor", "ratio");
  std::printf("%-34s %12.6f %12.6f %12.3f\n", "  std dev (mm)", r.sd, noise_mm, noise_mm > 0 ? r.sd / noise_mm : 0.0);
  std::printf("%-34s %12.6f %12s %12s\n", "  max - min (mm)", r.max - r.min, "", "");
  std::printf("%-34s %12.6f %12s %12s\n", "  mean (mm, ideal 1.05)", r.mean, "", "");
  std::printf("\n%-34s %12s %12s %12s\n", "cycle time (machine s)", "measured", "minimum", "ratio");
  std::printf("%-34s %12.4f %12.4f %12.4f\n", "  mean", ct.mean, mn.mean, mn.mean > 0 ? ct.mean / mn.mean : 0.0);
  std::printf("%-34s %12.4f %12.4f %12s\n", "  shortest", ct.min, mn.min, "");
  std::printf("%-34s %12.4f %12.4f %12s\n", "  longest", ct.max, mn.max, "");
  return failed == 0 ? 0 : 1;
}
