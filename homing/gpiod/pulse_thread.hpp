#pragma once
// The thread that runs the step generators: absolute deadlines on
// CLOCK_MONOTONIC every tick, so the pulse timing does not drift with the
// time the writes take. A late wake-up is not made up by a burst of ticks:
// the generators step toward where the motion is *now*.
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

 private:
  void run();

  std::vector<StepGenerator*> generators_;
  std::int64_t tick_ns_;
  int rt_priority_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

std::int64_t monotonic_now_ns();
std::int64_t realtime_now_ns();

}  // namespace homing::gpiod
