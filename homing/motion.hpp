#pragma once
// Acceleration-limited motion of one motor over one control period. The engine,
// the simulator and the step-pulse generator all run the same function, so the
// position the engine believes and the one the pulses produce never drift apart.
#include <array>
#include <cstddef>
#include <limits>
#include <optional>

namespace homing {

struct MotionState {
  double position_mm = 0;
  double velocity_mm_per_s = 0;
};

// Ramp toward target_velocity at acceleration, and never cross limit_mm (when
// has_limit): the motor stops dead there. A move-to sets the limit to its
// target, so a late control period can lengthen a move but never overshoot it.
struct MotionCommand {
  double target_velocity_mm_per_s = 0;
  double acceleration_mm_per_s2 = 0;  // <= 0 means "instantly"
  bool has_limit = false;
  double limit_mm = 0;
};

// One stretch of constant acceleration inside a period.
struct MotionPiece {
  double start_s = 0;
  double duration_s = 0;
  double position_mm = 0;
  double velocity_mm_per_s = 0;
  double acceleration_mm_per_s2 = 0;
  double position_at(double t_from_piece_start) const {
    return position_mm + velocity_mm_per_s * t_from_piece_start +
           0.5 * acceleration_mm_per_s2 * t_from_piece_start * t_from_piece_start;
  }
};

struct MotionPath {
  std::array<MotionPiece, 4> pieces{};
  std::size_t count = 0;
  MotionState end{};
};

MotionPath plan_path(const MotionState& start, const MotionCommand& command, double dt_s);
MotionState integrate(const MotionState& start, const MotionCommand& command, double dt_s);
double position_at(const MotionState& start, const MotionCommand& command, double t_s);

// First time in [0, dt] at which the path reaches position x, if it does.
std::optional<double> crossing_time(const MotionPath& path, double x_mm);

// Commands that the engine builds.
MotionCommand velocity_command(double velocity_mm_per_s, double acceleration_mm_per_s2);
MotionCommand stop_command(double acceleration_mm_per_s2);
// Trapezoidal move toward target: cruise at max_velocity, brake at acceleration
// so the motor comes to rest exactly on the target. Braking starts early
// enough for a control period up to kBrakingHorizon_s long, and is then a
// constant deceleration (<= acceleration) that ends on the target whatever
// the lengths of the periods that follow: no dead stop on the limit.
inline constexpr double kBrakingHorizon_s = 0.02;
// A move within this of its target has arrived (and one this long has nothing to do).
inline constexpr double kArrivedMm = 1e-9;
MotionCommand move_to_command(const MotionState& now, double target_mm,
                              double max_velocity_mm_per_s, double acceleration_mm_per_s2,
                              double dt_s);

constexpr double mm_per_min_to_mm_per_s(double v) { return v / 60.0; }
constexpr double stop_distance_mm(double v_mm_per_s, double a_mm_per_s2) {
  return a_mm_per_s2 > 0 ? v_mm_per_s * v_mm_per_s / (2.0 * a_mm_per_s2)
                         : std::numeric_limits<double>::infinity();
}

}  // namespace homing
