#pragma once
// Waiting for something a separate process does, bounded in time.
#include <chrono>
#include <functional>

namespace test_support {

// Polls pred every `every` until it holds or the timeout passes; whether it held.
bool wait_until(const std::function<bool()>& pred, std::chrono::milliseconds timeout,
                std::chrono::milliseconds every = std::chrono::milliseconds(10));

}  // namespace test_support
