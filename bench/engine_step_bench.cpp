// Cost of one engine control step with six axes homing at once (Google
// Benchmark). A lock-step run of engine and simulator records the inputs of
// every period of a complete six-axis home-all (all axes in sequence step 1);
// the benchmark then replays those inputs into a fresh engine, so only
// Engine::step is timed (not the simulator), on the very same trajectory.
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include "bench_axis.hpp"
#include "homing/engine.hpp"
#include "homing/sim/simulator.hpp"

using namespace homing;

namespace {

constexpr double kDt = 0.001;

Settings six_axes() {
  Settings settings;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisSettings& s = settings.axes[a];
    s = bench::switch_axis();
    s.soft_limit_min_mm = -1;
    s.soft_limit_max_mm = 500;
  }
  settings.global.sequence_steps = {0x3F, 0, 0, 0, 0, 0};  // all six together
  return settings;
}

sim::MachineConfig machine() {
  sim::MachineConfig m;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    sim::AxisConfig& c = m.axes[a];
    c.actual_position_mm = 20 + 7.0 * static_cast<double>(a);  // different distances: phases overlap
    c.sensor_min_mm = -1000;
    c.sensor_max_mm = 0;
    c.hysteresis_mm = 0.05;
    c.noise_mm = 0.002;
    c.hard_stop_min_mm = -5;
    c.hard_stop_max_mm = 1000;
  }
  m.seed = 7;
  return m;
}

// The inputs of every period from the home-all command to the end of the cycle.
const std::vector<Inputs>& recorded() {
  static const std::vector<Inputs> inputs = [] {
    std::vector<Inputs> out;
    const Settings settings = six_axes();
    Engine engine;
    sim::Simulator simulator(machine());
    auto step = [&](const Commands& cmd) {
      Inputs in = simulator.inputs();
      in.commands = cmd;
      out.push_back(in);
      const StepResult r = engine.step(settings, in, kDt);
      simulator.advance(r.outputs, kDt);
    };
    step(Commands{});
    Commands home;
    home.home_all = true;
    step(home);
    while (engine.status().homing && out.size() < 200'000) step(Commands{});
    if (engine.status().state != MachineState::homed) out.clear();
    return out;
  }();
  return inputs;
}

void BM_EngineStep_SixAxesHoming(benchmark::State& state) {
  const Settings settings = six_axes();
  const std::vector<Inputs>& inputs = recorded();
  if (inputs.empty()) {
    state.SkipWithError("the six-axis home-all did not end homed");
    return;
  }
  auto engine = std::make_unique<Engine>();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(engine->step(settings, inputs[i], kDt).outputs);
    if (++i == inputs.size()) {
      state.PauseTiming();
      engine = std::make_unique<Engine>();
      i = 0;
      state.ResumeTiming();
    }
  }
  state.counters["periods_per_cycle"] = static_cast<double>(inputs.size());
}
BENCHMARK(BM_EngineStep_SixAxesHoming);

void BM_EngineStep_SixAxesIdle(benchmark::State& state) {
  const Settings settings = six_axes();
  sim::Simulator simulator(machine());
  Engine engine;
  const Inputs in = simulator.inputs();
  for (auto _ : state) benchmark::DoNotOptimize(engine.step(settings, in, kDt).outputs);
}
BENCHMARK(BM_EngineStep_SixAxesIdle);

}  // namespace

BENCHMARK_MAIN();
