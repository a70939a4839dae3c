#pragma once
// The engine's contract with a machine: what the runtime asks of a backend
// every control period. Implemented by the simulator (homing/sim/simulator_io.hpp)
// and by GPIO on a real cabinet (homing/gpiod/gpiod_io.hpp), neither of which
// knows the runtime that drives it. Each control period:
//   io.advance(outputs, dt);   // the elapsed period ran these outputs
//   inputs = io.read();        // what happened in it
//   outputs = engine.step(settings, inputs, dt).outputs;
//   io.apply(outputs);         // at once: these run from now on
#include <span>

#include "io.hpp"

namespace homing {

namespace sim {
class SimulatorControls;
}

class MachineIo {
 public:
  virtual ~MachineIo() = default;
  // The elapsed period of dt_s ran `outputs` (those given to the last apply()).
  virtual void advance(const Outputs& outputs, double dt_s) = 0;
  virtual Inputs read() = 0;
  // Called right after the engine's step with the outputs it just computed:
  // outputs.axes[i].motor is the motor state at the start of the period now
  // beginning and .motion what to run from then on. Real hardware starts
  // them here (a backend that runs the outputs in advance(), like the
  // simulator, ignores it).
  virtual void apply(const Outputs& outputs) { (void)outputs; }
  // Called once at exit after motion has stopped: outputs to a safe state.
  virtual void shutdown() {}
  // While the engine is quiet (Engine::quiet) the runtime may leave the
  // machine running `outputs` (which move nothing) for longer than a
  // period. How long, in this machine's seconds, nothing changes by itself:
  // 0 when something is under way or may change within a period (the
  // runtime keeps its full rate: the default, for a backend that cannot
  // tell), the time to the next scheduled change, or infinity when only an
  // input event can change anything.
  virtual double quiet_for_s(const Outputs& outputs) const {
    (void)outputs;
    return 0;
  }
  // Descriptors that become readable when an input changes (line events):
  // the runtime waits on them while quiet and runs a period at once when one
  // does. read() drains what made them readable. Empty: the inputs are read
  // only in the periods that run (at the runtime's slow tick while quiet).
  virtual std::span<const int> event_fds() const { return {}; }
  // What only a simulated machine allows (the simulator unit: place a
  // carriage, inject a fault, press its e-stop); nullptr for a real one.
  virtual sim::SimulatorControls* simulator_controls() { return nullptr; }
};

}  // namespace homing
