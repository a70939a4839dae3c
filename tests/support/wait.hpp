#pragma once
// Waiting for something a separate process does, bounded in time.
#include <chrono>
#include <cstdint>
#include <functional>
#include <vector>

namespace test_support {

// Polls pred every `every` until it holds or the timeout passes; whether it held.
bool wait_until(const std::function<bool()>& pred, std::chrono::milliseconds timeout,
                std::chrono::milliseconds every = std::chrono::milliseconds(10));

// A watch over a window: `sample` taken every `every` from the start until
// `window_over` holds (or the timeout passes). "Nothing moved" is every sample
// equal to the first, across the whole window, not one reading before and
// one after (a carriage that moved and came back would pass those).
struct SteadyWatch {
  bool window_ended = false;           // window_over held before the timeout
  bool steady = true;                  // every sample equalled the first
  int samples = 0;
  std::vector<std::int64_t> first;     // the first sample
  std::vector<std::int64_t> changed;   // the first sample that differed from it
};
SteadyWatch watch_steady(const std::function<std::vector<std::int64_t>()>& sample,
                         const std::function<bool()>& window_over, std::chrono::milliseconds timeout,
                         std::chrono::milliseconds every = std::chrono::milliseconds(10));

}  // namespace test_support
