#pragma once
// The machine the control loop drives: the simulator by default, GPIO on a
// real cabinet. advance() runs the previous outputs for the elapsed time and
// then read() gives the inputs of that elapsed period.
#include "homing/io.hpp"

namespace server {

class MachineIo {
 public:
  virtual ~MachineIo() = default;
  virtual void advance(const homing::Outputs& outputs, double dt_s) = 0;
  virtual homing::Inputs read() = 0;
  // Called once at exit after motion has stopped: outputs to a safe state.
  virtual void shutdown() {}
};

}  // namespace server
