#pragma once
// The machine the control loop drives: the simulator by default, GPIO on a
// real cabinet. Each control period:
//   io.advance(outputs, dt);   // the elapsed period ran these outputs
//   inputs = io.read();        // what happened in it
//   outputs = engine.step(settings, inputs, dt).outputs;
//   io.apply(outputs);         // at once: these run from now on
#include "homing/io.hpp"

namespace server {

class MachineIo {
 public:
  virtual ~MachineIo() = default;
  // The elapsed period of dt_s ran `outputs` (those given to the last apply()).
  virtual void advance(const homing::Outputs& outputs, double dt_s) = 0;
  virtual homing::Inputs read() = 0;
  // Called right after the engine's step with the outputs it just computed:
  // outputs.axes[i].motor is the motor state at the start of the period now
  // beginning and .motion what to run from then on. Real hardware starts
  // them here (a backend that runs the outputs in advance(), like the
  // simulator, ignores it).
  virtual void apply(const homing::Outputs& outputs) { (void)outputs; }
  // Called once at exit after motion has stopped: outputs to a safe state.
  virtual void shutdown() {}
};

}  // namespace server
