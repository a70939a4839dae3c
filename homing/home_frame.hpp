#pragma once
// The settings that place an axis's coordinates on the machine: where the
// reference edge is found (mode, direction, polarity, gantry pairing, which
// edge of a home cam), where
// the axis rests from it (pull-off, switch compensation) and what coordinate
// it is given there (home position). An axis homed with one frame is not
// homed in another: the engine clears its homed state when its frame changes,
// so soft limits and moves never use coordinates measured for other settings.
#include "settings.hpp"

namespace homing {

struct HomeFrame {
  HomingMode mode = HomingMode::disabled;
  Direction direction = Direction::negative;
  bool sensor_nc = false;
  std::uint8_t slave_of = 0;
  SlaveMode slave_mode = SlaveMode::own_output;
  double pull_off_mm = 0;
  double switch_compensation_mm = 0;
  double home_position_mm = 0;
  // Only a home cam has two edges to choose from: for every other method the
  // setting places nothing, and a change of it unhomes nothing.
  CamEdge cam_edge = CamEdge::behind;
  friend bool operator==(const HomeFrame&, const HomeFrame&) = default;
};

// Of an axis's motion settings (gantry.hpp: a slave's are its master's).
constexpr HomeFrame home_frame(const AxisSettings& s) {
  return HomeFrame{s.mode,
                   s.direction,
                   s.sensor_nc,
                   s.slave_of,
                   s.slave_mode,
                   s.pull_off_mm,
                   s.switch_compensation_mm,
                   s.home_position_mm,
                   s.mode == HomingMode::home_cam ? s.cam_edge : CamEdge::behind};
}

}  // namespace homing
