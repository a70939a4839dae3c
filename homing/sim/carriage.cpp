#include "carriage.hpp"

#include <algorithm>
#include <cmath>

namespace homing::sim {
namespace {

void push(CarriagePath& path, double start_s, double duration_s, double x_mm, double v, double a,
          double slip_mm) {
  if (duration_s <= 0 || path.count >= path.pieces.size()) return;
  path.pieces[path.count++] = CarriagePiece{MotionPiece{start_s, duration_s, x_mm, v, a}, slip_mm};
}

// Time within a monotonic piece at which it reaches x (x between its ends).
double time_at(const MotionPiece& p, double x_mm) {
  MotionPath one;
  one.pieces[0] = MotionPiece{0, p.duration_s, p.position_mm, p.velocity_mm_per_s,
                              p.acceleration_mm_per_s2};
  one.count = 1;
  if (auto t = crossing_time(one, x_mm)) return *t;
  // Rounding at an end of the piece: take the nearer end.
  const double end = p.position_at(p.duration_s);
  return std::abs(x_mm - end) < std::abs(x_mm - p.position_mm) ? p.duration_s : 0.0;
}

// One monotonic stretch of the motor, in motor coordinates.
void follow(CarriagePath& path, const MotionPiece& m, const Stops& stops, double& slip_mm,
            double& carriage_mm) {
  const double motor_end = m.position_at(m.duration_s);
  const double carriage_end = motor_end + slip_mm;
  const bool up = motor_end > m.position_mm;
  const bool down = motor_end < m.position_mm;
  const double stop = up ? stops.max_mm : stops.min_mm;
  const bool hits = (up && carriage_end > stops.max_mm) || (down && carriage_end < stops.min_mm);
  if (!hits) {
    push(path, m.start_s, m.duration_s, m.position_mm + slip_mm, m.velocity_mm_per_s,
         m.acceleration_mm_per_s2, slip_mm);
    carriage_mm = carriage_end;
    return;
  }
  const bool already_there = up ? carriage_mm >= stops.max_mm : carriage_mm <= stops.min_mm;
  double t_contact = 0;
  if (!already_there) {
    t_contact = time_at(m, stop - slip_mm);
    push(path, m.start_s, t_contact, m.position_mm + slip_mm, m.velocity_mm_per_s,
         m.acceleration_mm_per_s2, slip_mm);
  }
  // Pushing on: the carriage stays, every further motor step is lost.
  slip_mm = stop - motor_end;
  push(path, m.start_s + t_contact, m.duration_s - t_contact, stop, 0, 0, slip_mm);
  carriage_mm = stop;
}

}  // namespace

CarriagePath carriage_path(const MotionState& motor_start, const MotionPath& motor,
                           double carriage_start_mm, const Stops& stops, bool drive_follows) {
  CarriagePath path;
  double carriage = std::clamp(carriage_start_mm, stops.min_mm, stops.max_mm);
  double slip = carriage - motor_start.position_mm;
  for (std::size_t i = 0; i < motor.count; ++i) {
    const MotionPiece& p = motor.pieces[i];
    if (!drive_follows) {
      const double motor_end = p.position_at(p.duration_s);
      push(path, p.start_s, p.duration_s, carriage, 0, 0, carriage - motor_end);
      continue;
    }
    // Split at the turning point so every stretch is monotonic.
    double t_turn = -1;
    if (p.acceleration_mm_per_s2 != 0) {
      t_turn = -p.velocity_mm_per_s / p.acceleration_mm_per_s2;
    }
    if (t_turn > 0 && t_turn < p.duration_s) {
      const MotionPiece first{p.start_s, t_turn, p.position_mm, p.velocity_mm_per_s,
                              p.acceleration_mm_per_s2};
      const MotionPiece second{p.start_s + t_turn, p.duration_s - t_turn, p.position_at(t_turn), 0,
                               p.acceleration_mm_per_s2};
      follow(path, first, stops, slip, carriage);
      follow(path, second, stops, slip, carriage);
    } else {
      follow(path, p, stops, slip, carriage);
    }
  }
  path.end_mm = carriage;
  return path;
}

}  // namespace homing::sim
