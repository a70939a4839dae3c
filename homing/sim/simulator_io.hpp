#pragma once
// The default machine: the simulator behind the engine's machine interface,
// stepped by whatever runs the control loop, with its extra controls (the
// simulator unit) as a capability of this backend.
#include "homing/machine_io.hpp"
#include "simulator.hpp"
#include "simulator_controls.hpp"

namespace homing::sim {

class SimulatorIo final : public MachineIo {
 public:
  explicit SimulatorIo(const MachineConfig& config) : sim_(config) {}
  // A copy of a simulator built before: seeding the random sources costs more
  // than a short run (fuzzers build a backend per input).
  explicit SimulatorIo(const Simulator& prototype) : sim_(prototype) {}
  SimulatorIo(const SimulatorIo&) = delete;
  SimulatorIo& operator=(const SimulatorIo&) = delete;

  void advance(const Outputs& outputs, double dt_s) override {
    if (dt_s > 0) sim_.advance(outputs, dt_s);
  }
  Inputs read() override { return sim_.inputs(); }
  double quiet_for_s(const Outputs& outputs) const override { return sim_.quiet_for_s(outputs); }
  SimulatorControls* simulator_controls() override { return &controls_; }

 private:
  Simulator sim_;
  SimulatorControls controls_{sim_};
};

}  // namespace homing::sim
