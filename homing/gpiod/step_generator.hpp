#pragma once
// Step/direction pulses for one axis. The control thread hands over the
// engine's motion, one segment per control period (motor state at its start
// + the command, exactly what the engine integrates); the pulse thread calls
// tick() at a fine period and steps toward the position that homing::
// position_at gives for that instant. The commanded position is an integer
// step count, so a step is never lost or invented: after any motion the
// steps emitted equal round(engine position * steps_per_unit).
//
// Each segment starts at the instant the engine's period began (its motor
// state is the engine's state at that instant): the backend hands it over
// right after the engine's step (GpiodIo::apply), a few microseconds into the
// period, and until then the previous segment runs on, as the engine's own
// motion does when a period is late. The pulses are thus where the engine
// computed them, and so is the reference edge. A playback delay (config
// playback_delay_us, 0 by default) shifts the whole timeline later and the
// reference by feed x delay.
//
// One tick makes at most one edge on the step line (rising, then falling on
// the next tick), so the pulse width is one tick and the maximum step rate
// is 1 / (2 tick). A direction change waits dir_setup before the next rising
// edge and is only made while the step line is low.
#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "homing/motion.hpp"
#include "line_api.hpp"

namespace homing::gpiod {

struct Segment {
  std::int64_t start_ns = 0;  // on the pulse thread's clock (CLOCK_MONOTONIC)
  MotionState motor{};
  MotionCommand command{};
};

class StepGenerator {
 public:
  StepGenerator(LineApi& lines, LineId step, LineId dir, double steps_per_unit, std::int64_t dir_setup_ns);

  // Control thread. Starts must not go backwards.
  void push(const Segment& segment);
  // Pulse thread (tests call it directly with synthetic times).
  void tick(std::int64_t now_ns);
  // Drives the step line low (at exit, after the pulse thread stopped).
  void idle();

  std::int64_t position_steps() const { return position_steps_.load(); }
  // After the last tick: nothing left to emit until a new segment comes (the
  // step line low, the commanded position reached, the motion playing at rest
  // and none queued behind it), so the pulse thread may sleep until push().
  bool resting() const { return resting_.load(); }
  // Largest distance, in steps, between commanded and emitted: above a few
  // steps the commanded rate exceeded 1 / (2 tick) or the thread was late.
  std::int64_t max_lag_steps() const { return max_lag_steps_.load(); }
  // First write error on the step or dir line, if any (the axis is then faulty).
  bool failed() const { return failed_.load(); }
  std::string failure() const;
  double steps_per_unit() const { return steps_per_unit_; }

 private:
  bool current_segment(std::int64_t now_ns, Segment& out, bool& more_queued);
  bool write(LineId line, bool value);

  LineApi& lines_;
  LineId step_line_;
  LineId dir_line_;
  double steps_per_unit_;
  std::int64_t dir_setup_ns_;

  mutable std::mutex mutex_;  // guards the segment ring and failure text
  static constexpr std::size_t kRing = 32;
  std::array<Segment, kRing> ring_{};
  std::size_t head_ = 0;   // oldest
  std::size_t count_ = 0;
  std::string failure_;

  // Pulse-thread state.
  bool step_high_ = false;
  bool dir_positive_ = false;  // the dir line's logical level: 1 = positive
  std::int64_t dir_changed_ns_ = INT64_MIN / 2;
  std::atomic<std::int64_t> position_steps_{0};
  std::atomic<std::int64_t> max_lag_steps_{0};
  std::atomic<bool> failed_{false};
  std::atomic<bool> resting_{true};
};

}  // namespace homing::gpiod
