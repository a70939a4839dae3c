#include "step_generator.hpp"

#include <cmath>
#include <cstdlib>

namespace homing::gpiod {

StepGenerator::StepGenerator(LineApi& lines, LineId step, LineId dir, double steps_per_unit,
                             std::int64_t dir_setup_ns)
    : lines_(lines), step_line_(step), dir_line_(dir), steps_per_unit_(steps_per_unit), dir_setup_ns_(dir_setup_ns) {}

void StepGenerator::push(const Segment& segment) {
  std::lock_guard lock(mutex_);
  if (count_ == kRing) {  // the pulse thread stalled: the oldest is long past
    head_ = (head_ + 1) % kRing;
    --count_;
  }
  ring_[(head_ + count_) % kRing] = segment;
  ++count_;
}

// The segment playing at now: the newest one that has started. Older ones
// are dropped; a segment is extended past its nominal end until the next
// one starts, which is what the engine does when a period runs late.
bool StepGenerator::current_segment(std::int64_t now_ns, Segment& out, bool& more_queued) {
  std::lock_guard lock(mutex_);
  while (count_ >= 2 && ring_[(head_ + 1) % kRing].start_ns <= now_ns) {
    head_ = (head_ + 1) % kRing;
    --count_;
  }
  more_queued = count_ >= 2;
  if (count_ == 0 || ring_[head_].start_ns > now_ns) {
    more_queued = count_ != 0;  // one still to start: not at rest
    return false;
  }
  out = ring_[head_];
  return true;
}

bool StepGenerator::write(LineId line, bool value) {
  auto r = lines_.set_value(line, value);
  if (r) return true;
  if (!failed_.exchange(true)) {
    std::lock_guard lock(mutex_);
    failure_ = r.error();
  }
  return false;
}

std::string StepGenerator::failure() const {
  std::lock_guard lock(mutex_);
  return failure_;
}

void StepGenerator::tick(std::int64_t now_ns) {
  resting_ = false;
  if (failed_) {
    resting_ = true;  // it emits nothing more
    return;
  }
  if (step_high_) {  // second half of a pulse
    if (write(step_line_, false)) step_high_ = false;
    return;
  }
  Segment seg;
  bool more_queued = false;
  if (!current_segment(now_ns, seg, more_queued)) {
    resting_ = !more_queued;  // nothing handed over yet
    return;
  }
  const double t_s = static_cast<double>(now_ns - seg.start_ns) * 1e-9;
  const double position_mm = position_at(seg.motor, seg.command, t_s);
  const std::int64_t target = std::llround(position_mm * steps_per_unit_);
  const std::int64_t diff = target - position_steps_.load();
  const std::int64_t lag = std::llabs(diff);
  if (lag > max_lag_steps_.load()) max_lag_steps_ = lag;
  if (diff == 0) {
    // A segment at rest and staying there plays the same position for ever.
    resting_ = !more_queued && seg.motor.velocity_mm_per_s == 0 && seg.command.target_velocity_mm_per_s == 0;
    return;
  }
  const bool positive = diff > 0;
  if (positive != dir_positive_) {
    if (!write(dir_line_, positive)) return;
    dir_positive_ = positive;
    dir_changed_ns_ = now_ns;
  }
  if (now_ns - dir_changed_ns_ < dir_setup_ns_) return;  // let the drive see the new direction first
  if (!write(step_line_, true)) return;
  step_high_ = true;
  position_steps_ += positive ? 1 : -1;
}

void StepGenerator::idle() {
  if (step_high_ && lines_.set_value(step_line_, false)) step_high_ = false;
}

}  // namespace homing::gpiod
