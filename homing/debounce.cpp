#include "debounce.hpp"

namespace homing {

void Debouncer::reset(bool level, double now_s) {
  stable_ = raw_ = level;
  pending_ = false;
  last_change_t_ = now_s;
}

void Debouncer::transition(double t_s, double x_mm) {
  raw_ = !raw_;
  ++transitions_;
  if (!pending_ && raw_ != stable_) {
    pending_ = true;
    first_t_ = t_s;
    first_x_ = x_mm;
  }
  last_change_t_ = t_s;
}

bool Debouncer::settle(double now_s, double debounce_s, AcceptedEdge& out) {
  if (!pending_) return false;
  // A tiny tolerance so a debounce equal to a whole number of periods is not
  // pushed one period later by rounding.
  if (now_s - last_change_t_ + 1e-9 < debounce_s) return false;
  pending_ = false;
  if (raw_ == stable_) return false;  // a glitch that came back: rejected
  stable_ = raw_;
  ++accepted_;
  out = AcceptedEdge{stable_, first_t_, first_x_};
  return true;
}

}  // namespace homing
