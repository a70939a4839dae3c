#pragma once
// The physical home switch of one axis: a cam that holds it active, hysteresis
// on release, and independent normal noise on every edge's position. Knows
// nothing of wiring, faults or bounce; those act on the contact downstream.
#include <array>
#include <cstddef>
#include <cstdint>
#include <random>

#include "config.hpp"
#include "homing/motion.hpp"

namespace homing::sim {

struct SensorEvent {
  double time_s = 0;  // from the period start
  bool to_active = false;
  double actual_mm = 0;
  double slip_mm = 0;  // carriage - motor at that instant
};

struct SensorEvents {
  // A monotonic piece enters and leaves the cam at most once each.
  std::array<SensorEvent, 40> items{};
  std::size_t count = 0;
  void add(const SensorEvent& e) {
    if (count < items.size()) items[count++] = e;
  }
};

class HomeSensor {
 public:
  void reseed(std::uint64_t seed, std::size_t axis);
  // New cam, hysteresis or noise: fresh thresholds for the current state; the
  // state itself is corrected by the next settle_at().
  void configure(const AxisConfig& config);
  bool active() const { return active_; }
  // Brings the state in line with a carriage standing at x (after a jump or a
  // knob change). True when the state changed.
  bool settle_at(double x_mm);
  // Edges while the carriage runs one monotonic piece.
  void sweep(const MotionPiece& piece, double slip_mm, SensorEvents& out);

 private:
  double noise() { return noise_mm_ * normal_(rng_); }
  void draw_on(const double* edge_mm);
  void draw_off(const double* edge_mm);
  void change(double x_mm);

  double min_mm_ = 0, max_mm_ = -1;  // empty until configured
  double hysteresis_mm_ = 0, noise_mm_ = 0;
  bool active_ = false;
  // Active when inactive and the carriage reaches [on_lo, on_hi]; inactive when
  // active and the carriage leaves [off_lo, off_hi]. Drawn afresh at each edge.
  double on_lo_mm_ = 0, on_hi_mm_ = 0, off_lo_mm_ = 0, off_hi_mm_ = 0;
  std::mt19937_64 rng_{};
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace homing::sim
