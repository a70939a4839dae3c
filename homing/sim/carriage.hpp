#pragma once
// Turns the motor's path over one period into the carriage's path: the carriage
// is the motor plus a slip, except that mechanical stops hold it (the motor
// loses steps, the slip changes) and a faulted drive does not move it at all.
#include <array>
#include <cstddef>

#include "homing/motion.hpp"

namespace homing::sim {

// A stretch of carriage motion that is monotonic (or at rest), so each position
// is passed at most once: crossings are then unique and ordered.
struct CarriagePiece {
  MotionPiece motion{};  // in carriage coordinates, times from the period start
  double slip_mm = 0;    // carriage - motor during this piece (constant while following)
};

struct CarriagePath {
  // Each motor piece splits at most at its turning point and at a stop.
  std::array<CarriagePiece, 16> pieces{};
  std::size_t count = 0;
  double end_mm = 0;
};

struct Stops {
  double min_mm = -1e9;
  double max_mm = 1e9;
};

CarriagePath carriage_path(const MotionState& motor_start, const MotionPath& motor,
                           double carriage_start_mm, const Stops& stops, bool drive_follows);

}  // namespace homing::sim
