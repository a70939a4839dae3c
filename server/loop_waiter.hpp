#pragma once
// How the control thread waits between periods. At the full rate it sleeps
// to an absolute deadline whatever happens meanwhile, so a period never
// starts early; while quiet (nothing moves, nothing pending) it waits for a
// deadline far off or for a wake: a command, a simulator edit or any other
// mailbox news (wake()), or an input event (a backend's line-event
// descriptors). A seam: the loop tests give it a fake that records every
// wait on a clock of their own, so they assert on the sequence of periods,
// not on wall time.
#include <cstdint>
#include <memory>
#include <span>

namespace server {

class LoopWaiter {
 public:
  virtual ~LoopWaiter() = default;
  // Nanoseconds on CLOCK_MONOTONIC (the fake's own clock in tests).
  virtual std::int64_t now_ns() = 0;
  // Sleeps until deadline_ns: nothing ends it early.
  virtual void sleep_until(std::int64_t deadline_ns) = 0;
  // Waits until deadline_ns, or less: once wake() was called since the last
  // wait_until returned (a wake before the wait is not lost), or once one of
  // fds is readable. True when it ended before the deadline.
  virtual bool wait_until(std::int64_t deadline_ns, std::span<const int> fds) = 0;
  // Any thread: ends the wait under way, or the next one, at once.
  virtual void wake() = 0;
};

// clock_nanosleep(TIMER_ABSTIME) for sleep_until; ppoll on an eventfd (the
// wakes) and the given descriptors for wait_until.
std::unique_ptr<LoopWaiter> make_poll_waiter();

}  // namespace server
