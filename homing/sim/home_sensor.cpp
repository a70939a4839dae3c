#include "home_sensor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace homing::sim {
namespace {

// Keeps the threshold just crossed apart from the next one, so a carriage
// standing on an edge cannot chatter at zero hysteresis.
constexpr double kSeparation_mm = 1e-9;
constexpr double kInf = std::numeric_limits<double>::infinity();

double time_at(const MotionPiece& p, double x_mm) {
  MotionPath one;
  one.pieces[0] = MotionPiece{0, p.duration_s, p.position_mm, p.velocity_mm_per_s,
                              p.acceleration_mm_per_s2};
  one.count = 1;
  if (auto t = crossing_time(one, x_mm)) return p.start_s + *t;
  const double end = p.position_at(p.duration_s);
  return p.start_s +
         (std::abs(x_mm - end) < std::abs(x_mm - p.position_mm) ? p.duration_s : 0.0);
}

}  // namespace

void HomeSensor::reseed(std::uint64_t seed, std::size_t axis) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(axis), 0x5e45u};
  rng_.seed(seq);
  normal_.reset();
}

void HomeSensor::configure(const AxisConfig& config) {
  min_mm_ = config.sensor_min_mm;
  max_mm_ = config.sensor_max_mm;
  hysteresis_mm_ = std::max(0.0, config.hysteresis_mm);
  noise_mm_ = std::max(0.0, config.noise_mm);
  if (active_) draw_off(nullptr); else draw_on(nullptr);
}

void HomeSensor::draw_on(const double* edge_mm) {
  // Always draw both, so the sequence does not depend on which edge comes next.
  const double n_lo = noise(), n_hi = noise();
  if (max_mm_ < min_mm_) {
    on_lo_mm_ = kInf;
    on_hi_mm_ = -kInf;
    return;
  }
  on_lo_mm_ = min_mm_ + n_lo;
  on_hi_mm_ = max_mm_ + n_hi;
  if (on_lo_mm_ > on_hi_mm_) on_lo_mm_ = on_hi_mm_ = 0.5 * (on_lo_mm_ + on_hi_mm_);
  if (!edge_mm) return;
  // Just released at *edge_mm: the cam must lie beyond it, or the switch would re-trigger.
  if (*edge_mm < 0.5 * (min_mm_ + max_mm_)) {
    on_lo_mm_ = std::max(on_lo_mm_, *edge_mm + kSeparation_mm);
    on_hi_mm_ = std::max(on_hi_mm_, on_lo_mm_);
  } else {
    on_hi_mm_ = std::min(on_hi_mm_, *edge_mm - kSeparation_mm);
    on_lo_mm_ = std::min(on_lo_mm_, on_hi_mm_);
  }
}

void HomeSensor::draw_off(const double* edge_mm) {
  const double n_lo = noise(), n_hi = noise();
  if (max_mm_ < min_mm_) {
    off_lo_mm_ = kInf;  // no cam: any position releases
    off_hi_mm_ = -kInf;
    return;
  }
  off_lo_mm_ = min_mm_ - hysteresis_mm_ + n_lo;
  off_hi_mm_ = max_mm_ + hysteresis_mm_ + n_hi;
  if (!edge_mm) return;
  off_lo_mm_ = std::min(off_lo_mm_, *edge_mm - kSeparation_mm);
  off_hi_mm_ = std::max(off_hi_mm_, *edge_mm + kSeparation_mm);
}

void HomeSensor::change(double x_mm) {
  active_ = !active_;
  if (active_) draw_off(&x_mm); else draw_on(&x_mm);
}

bool HomeSensor::settle_at(double x_mm) {
  const bool wrong = active_ ? (x_mm < off_lo_mm_ || x_mm > off_hi_mm_)
                             : (x_mm >= on_lo_mm_ && x_mm <= on_hi_mm_);
  if (wrong) change(x_mm);
  return wrong;
}

void HomeSensor::sweep(const MotionPiece& piece, double slip_mm, SensorEvents& out) {
  const double end_mm = piece.position_at(piece.duration_s);
  const bool up = end_mm > piece.position_mm;
  if (end_mm == piece.position_mm) return;
  double x = piece.position_mm;
  // Each change moves the next threshold further along, so this ends; the
  // bound only guards against rounding.
  for (int guard = 0; guard < 8; ++guard) {
    double th;
    bool reached;
    if (up) {
      th = active_ ? off_hi_mm_ : on_lo_mm_;
      reached = x < th && th <= end_mm && (active_ || on_lo_mm_ <= on_hi_mm_);
    } else {
      th = active_ ? off_lo_mm_ : on_hi_mm_;
      reached = end_mm <= th && th < x && (active_ || on_lo_mm_ <= on_hi_mm_);
    }
    if (!reached) return;
    change(th);
    out.add(SensorEvent{time_at(piece, th), active_, th, slip_mm});
    x = th;
  }
}

}  // namespace homing::sim
