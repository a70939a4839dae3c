#include "index_pulses.hpp"

#include <cmath>

namespace homing::sim {

void add_index_crossings(const MotionPiece& piece, double pitch_mm, double offset_mm,
                         InputEdges& edges) {
  if (pitch_mm <= 0) return;
  const double start = piece.position_mm;
  const double end = piece.position_at(piece.duration_s);
  if (end == start) return;
  const bool up = end > start;
  const double k0 = (start - offset_mm) / pitch_mm;
  double k = up ? std::floor(k0) + 1 : std::ceil(k0) - 1;
  MotionPath one;
  one.pieces[0] = MotionPiece{0, piece.duration_s, start, piece.velocity_mm_per_s,
                              piece.acceleration_mm_per_s2};
  one.count = 1;
  // More pulses than InputEdges holds only sets overflow, so stop there.
  while (!edges.overflow) {
    const double x = offset_mm + k * pitch_mm;
    if (up ? x > end : x < end) return;
    const auto t = crossing_time(one, x);
    edges.add(piece.start_s + (t ? *t : piece.duration_s));
    k += up ? 1 : -1;
  }
}

}  // namespace homing::sim
