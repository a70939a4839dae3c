#include "homing_drive.hpp"

#include <algorithm>
#include <cmath>

namespace homing::sim {

bool HomingDrive::advance(bool request, const AxisConfig& c, double min_mm, double max_mm, double& carriage_mm,
                          double dt_s) {
  if (c.fault == Fault::drive_done_lost) referenced_ = false;  // lost for good: only a new homing restores it
  const bool rising = request && !prev_request_;
  prev_request_ = request;
  if (rising) {
    if (c.fault == Fault::drive_answers_at_once) {
      referenced_ = true;
      homing_ = false;
      return false;
    }
    referenced_ = false;
    homing_ = true;
    arrived_ = false;
    answer_left_s_ = c.drive_answer_ms / 1000.0;
  }
  if (!request) homing_ = false;  // a request dropped mid-homing stops the drive where it is
  if (!homing_ || c.fault == Fault::drive_never_answers || c.fault == Fault::drive_fault) return false;

  double left_s = dt_s;
  bool moved = false;
  if (!arrived_) {
    const double target = std::clamp(c.drive_home_position_mm, min_mm, std::max(min_mm, max_mm));
    const double v = std::max(c.drive_speed_mm_per_min, 1e-9) / 60.0;
    const double to_go = target - carriage_mm;
    const double reach = v * dt_s;
    if (std::abs(to_go) > reach) {
      carriage_mm += std::copysign(reach, to_go);
      return true;
    }
    moved = to_go != 0;
    carriage_mm = target;
    arrived_ = true;
    left_s = dt_s - std::abs(to_go) / v;
  }
  answer_left_s_ -= left_s;
  if (answer_left_s_ <= 0) {
    referenced_ = true;
    homing_ = false;
  }
  return moved;
}

}  // namespace homing::sim
