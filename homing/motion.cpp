#include "motion.hpp"

#include <algorithm>
#include <cmath>

namespace homing {
namespace {

constexpr double kEps = 1e-12;

void push_piece(MotionPath& path, double start, double duration, double x, double v, double a) {
  if (duration <= 0) return;
  path.pieces[path.count++] = MotionPiece{start, duration, x, v, a};
}

// Earliest t in [0, piece.duration] where the piece reaches x.
std::optional<double> piece_crossing(const MotionPiece& p, double x) {
  const double a = 0.5 * p.acceleration_mm_per_s2;
  const double b = p.velocity_mm_per_s;
  const double c = p.position_mm - x;
  std::optional<double> best;
  auto consider = [&](double t) {
    if (t >= -kEps && t <= p.duration_s + kEps) {
      t = std::clamp(t, 0.0, p.duration_s);
      if (!best || t < *best) best = t;
    }
  };
  if (std::abs(c) <= kEps) return 0.0;
  if (std::abs(a) < kEps) {
    if (std::abs(b) > kEps) consider(-c / b);
    return best;
  }
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return best;
  const double sq = std::sqrt(disc);
  consider((-b - sq) / (2 * a));
  consider((-b + sq) / (2 * a));
  return best;
}

}  // namespace

MotionPath plan_path(const MotionState& start, const MotionCommand& cmd, double dt) {
  MotionPath path;
  dt = std::max(dt, 0.0);
  const double v0 = start.velocity_mm_per_s;
  const double vt = cmd.target_velocity_mm_per_s;
  const double dv = vt - v0;
  double t_ramp = 0;
  double accel = 0;
  if (std::abs(dv) > kEps) {
    if (cmd.acceleration_mm_per_s2 > 0) {
      t_ramp = std::min(dt, std::abs(dv) / cmd.acceleration_mm_per_s2);
      accel = dv > 0 ? cmd.acceleration_mm_per_s2 : -cmd.acceleration_mm_per_s2;
    }
  }
  // Unclamped pieces: ramp, then cruise (or an instant velocity change).
  MotionPath raw;
  double x = start.position_mm;
  double v = v0;
  if (t_ramp > 0) {
    push_piece(raw, 0, t_ramp, x, v, accel);
    x += v * t_ramp + 0.5 * accel * t_ramp * t_ramp;
    v += accel * t_ramp;
  }
  if (t_ramp < dt) {
    if (cmd.acceleration_mm_per_s2 <= 0 || std::abs(v - vt) <= 1e-9) v = vt;
    push_piece(raw, t_ramp, dt - t_ramp, x, v, 0);
    x += v * (dt - t_ramp);
  }
  raw.end = MotionState{x, v};
  if (!cmd.has_limit) {
    raw.end = raw.count ? raw.end : start;
    return raw;
  }
  // Clamp at the limit: the motor stops dead where it first reaches it.
  const bool at_limit = std::abs(start.position_mm - cmd.limit_mm) <= 1e-9;
  if (at_limit) {
    push_piece(path, 0, dt, cmd.limit_mm, 0, 0);
    path.end = MotionState{cmd.limit_mm, 0};
    return path;
  }
  for (std::size_t i = 0; i < raw.count; ++i) {
    const MotionPiece& p = raw.pieces[i];
    if (auto t = piece_crossing(p, cmd.limit_mm)) {
      push_piece(path, p.start_s, *t, p.position_mm, p.velocity_mm_per_s, p.acceleration_mm_per_s2);
      push_piece(path, p.start_s + *t, dt - (p.start_s + *t), cmd.limit_mm, 0, 0);
      path.end = MotionState{cmd.limit_mm, 0};
      return path;
    }
    path.pieces[path.count++] = p;
  }
  path.end = raw.count ? raw.end : start;
  return path;
}

MotionState integrate(const MotionState& start, const MotionCommand& cmd, double dt) {
  if (dt <= 0) return start;
  return plan_path(start, cmd, dt).end;
}

double position_at(const MotionState& start, const MotionCommand& cmd, double t) {
  return integrate(start, cmd, t).position_mm;
}

std::optional<double> crossing_time(const MotionPath& path, double x) {
  for (std::size_t i = 0; i < path.count; ++i) {
    const MotionPiece& p = path.pieces[i];
    if (auto t = piece_crossing(p, x)) return p.start_s + *t;
  }
  return std::nullopt;
}

MotionCommand velocity_command(double v, double a) { return MotionCommand{v, a, false, 0}; }

MotionCommand stop_command(double a) { return MotionCommand{0, a, false, 0}; }

MotionCommand move_to_command(const MotionState& now, double target, double vmax, double a,
                              double dt) {
  const double d = target - now.position_mm;
  const double dir = d >= 0 ? 1.0 : -1.0;
  const double dist = std::abs(d);
  if (dist <= 1e-12) return MotionCommand{0, a, true, target};
  const double v_toward = now.velocity_mm_per_s * dir;  // > 0: already heading for the target
  // Look further ahead than one period: a late period must not carry the
  // motor past the point where braking at `a` still ends on the target.
  const double horizon = std::max(dt, kBrakingHorizon_s);
  if (a > 0 && v_toward > 0 && v_toward * horizon + v_toward * v_toward / (2.0 * a) >= dist) {
    // Brake now with the constant deceleration that ends exactly on the
    // target. Constant deceleration is exact whatever the period lengths.
    const double needed = v_toward * v_toward / (2.0 * dist);
    // Too fast to stop there at `a` (the target came closer than the stop,
    // e.g. an edge seen a period late): brake at `a`, pass it, come back,
    // rather than stop harder than the drive can.
    if (needed > a * (1 + 1e-9)) return MotionCommand{0, a, false, 0};
    return MotionCommand{0, std::max(needed, 1e-9), true, target};
  }
  // Cruise no faster than lets a whole horizon at that speed still leave
  // the stop distance: v·h + v²/2a ≤ dist. (Half a horizon, as this once
  // said, let a late period at 60,000 mm/min carry a jog past its soft limit:
  // campaign seed 2109 after the feedrates reached the registers' maxima.)
  double v = std::abs(vmax);
  if (a > 0) {
    const double ad = a * horizon;
    v = std::min(v, std::max(0.0, -ad + std::sqrt(ad * ad + 2.0 * a * dist)));
  }
  // Never stall short of the target: creep the last micrometres.
  if (v < 1e-3) v = std::min(std::abs(vmax), 1e-3 + dist / std::max(dt, 1e-6));
  return MotionCommand{dir * v, a, true, target};
}

}  // namespace homing
