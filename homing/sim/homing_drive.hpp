#pragma once
// The drive of drive-performed homing (drive mode): a servo drive that homes
// itself. On a rising home request it drops home done, moves the carriage to
// its own home (its own sensor) at its own speed, waits its answer time and
// reports home done, which stays on while its reference holds. A request
// dropped during its homing stops it where it is. Faults: never finishing,
// answering at once, losing the reference (config.hpp).
#include "config.hpp"

namespace homing::sim {

class HomingDrive {
 public:
  // One period of dt_s with the request as the engine drives it. Moves
  // carriage_mm (within min_mm..max_mm) when it homes; true while it moves it.
  bool advance(bool request, const AxisConfig& config, double min_mm, double max_mm, double& carriage_mm,
               double dt_s);
  bool done(const AxisConfig& config) const { return referenced_ && config.fault != Fault::drive_done_lost; }
  bool homing() const { return homing_; }
  // Left with this request it does nothing: not homing, no new request to answer.
  bool at_rest(bool request) const { return !homing_ && request == prev_request_; }

 private:
  bool referenced_ = false;  // powered up unreferenced
  bool homing_ = false;
  bool arrived_ = false;
  bool prev_request_ = false;
  double answer_left_s_ = 0;
};

}  // namespace homing::sim
