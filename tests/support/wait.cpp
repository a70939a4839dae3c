#include "tests/support/wait.hpp"

#include <thread>

namespace test_support {

bool wait_until(const std::function<bool()>& pred, std::chrono::milliseconds timeout, std::chrono::milliseconds every) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (pred()) return true;
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(every);
  }
}

SteadyWatch watch_steady(const std::function<std::vector<std::int64_t>()>& sample,
                         const std::function<bool()>& window_over, std::chrono::milliseconds timeout,
                         std::chrono::milliseconds every) {
  SteadyWatch w;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  w.first = sample();
  w.samples = 1;
  for (;;) {
    // The window's end is decided before the last sample, so that sample
    // belongs to the window too.
    const bool over = window_over();
    const auto now = sample();
    ++w.samples;
    if (w.steady && now != w.first) {
      w.steady = false;
      w.changed = now;
    }
    if (over) {
      w.window_ended = true;
      return w;
    }
    if (std::chrono::steady_clock::now() >= deadline) return w;
    std::this_thread::sleep_for(every);
  }
}

}  // namespace test_support
