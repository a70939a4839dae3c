#pragma once
// The axis the engine benchmarks home (engine_step_bench, repeatability): a
// switch-and-release home toward negative, 1200 mm/min seek, 60 mm/min latch,
// 500 mm/s^2, within 300 mm.
#include "homing/settings.hpp"

namespace bench {

inline homing::AxisSettings switch_axis() {
  homing::AxisSettings s;
  s.mode = homing::HomingMode::switch_release;
  s.direction = homing::Direction::negative;
  s.seek_feedrate_mm_per_min = 1200;
  s.latch_feedrate_mm_per_min = 60;
  s.acceleration_mm_per_s2 = 500;
  s.max_seek_travel_mm = 300;
  s.max_stop_distance_mm = 10;
  s.max_backoff_mm = 10;
  s.pull_off_mm = 1;
  s.jog_feedrate_mm_per_min = 600;
  return s;
}

}  // namespace bench
