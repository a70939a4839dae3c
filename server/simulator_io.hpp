#pragma once
// The default machine: the simulator, stepped by the control loop.
#include "homing/sim/simulator.hpp"
#include "machine_io.hpp"

namespace server {

class SimulatorIo final : public MachineIo {
 public:
  explicit SimulatorIo(const homing::sim::MachineConfig& config) : sim_(config) {}
  void advance(const homing::Outputs& outputs, double dt_s) override {
    if (dt_s > 0) sim_.advance(outputs, dt_s);
  }
  homing::Inputs read() override { return sim_.inputs(); }
  homing::sim::Simulator& sim() { return sim_; }

 private:
  homing::sim::Simulator sim_;
};

}  // namespace server
