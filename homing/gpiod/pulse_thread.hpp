#pragma once
// The thread that runs the step generators: absolute deadlines on
// CLOCK_MONOTONIC every tick, so the pulse timing does not drift with the
// time the writes take. A late wake-up is not made up by a burst of ticks:
// the generators step toward where the motion is *now*. Once every generator
// rests (nothing left to emit), the thread sleeps until wake() says a segment
// came: an idle machine costs no tick at all.
#include <atomic>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "step_generator.hpp"

namespace homing::gpiod {

class PulseThread {
 public:
  PulseThread(std::vector<StepGenerator*> generators, std::int64_t tick_ns, int rt_priority);
  ~PulseThread();
  PulseThread(const PulseThread&) = delete;
  PulseThread& operator=(const PulseThread&) = delete;

  // Returns a warning when the real-time priority could not be set.
  std::string start();
  void stop();
  // Control thread, after it handed the generators their segments.
  void wake();
  // Loop turns so far (a tick of every generator each): what a test watches
  // to see the thread sleep while nothing moves.
  std::uint64_t turns() const { return turns_.load(); }

 private:
  void run();

  std::vector<StepGenerator*> generators_;
  std::int64_t tick_ns_;
  int rt_priority_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> wakes_{0};  // wake() calls: the sleep waits for this to change
  std::atomic<std::uint64_t> turns_{0};
  std::thread thread_;
};

std::int64_t monotonic_now_ns();
std::int64_t realtime_now_ns();

}  // namespace homing::gpiod
