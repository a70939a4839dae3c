#include "loop_waiter.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace server {
namespace {

std::int64_t clock_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

timespec to_timespec(std::int64_t ns) {
  return timespec{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
}

class PollWaiter final : public LoopWaiter {
 public:
  PollWaiter() : wake_fd_(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
    if (wake_fd_ < 0) throw std::runtime_error(std::string("control loop: eventfd: ") + std::strerror(errno));
  }
  ~PollWaiter() override { close(wake_fd_); }
  PollWaiter(const PollWaiter&) = delete;
  PollWaiter& operator=(const PollWaiter&) = delete;

  std::int64_t now_ns() override { return clock_now_ns(); }

  void sleep_until(std::int64_t deadline_ns) override {
    const timespec ts = to_timespec(deadline_ns);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {}
  }

  bool wait_until(std::int64_t deadline_ns, std::span<const int> fds) override {
    // waiting_ before pending_, and pending_ before waiting_ in wake(), both
    // sequentially consistent: either this sees the wake's pending_, or the
    // wake sees waiting_ and writes the eventfd. No wake is lost.
    waiting_.store(true);
    if (pending_.exchange(false)) {
      waiting_.store(false);
      drain();
      return true;
    }
    polled_.assign(1, pollfd{wake_fd_, POLLIN, 0});
    for (const int fd : fds) polled_.push_back(pollfd{fd, POLLIN, 0});
    bool early = false;
    for (;;) {
      const std::int64_t left_ns = deadline_ns - clock_now_ns();
      const timespec timeout = to_timespec(left_ns > 0 ? left_ns : 0);
      const int n = ppoll(polled_.data(), polled_.size(), &timeout, nullptr);
      if (n < 0 && errno == EINTR) continue;
      early = n > 0;  // an error (a descriptor gone bad) also ends the wait: the period that follows reads the inputs
      if (n < 0) early = true;
      break;
    }
    waiting_.store(false);
    // The period about to run takes whatever the wakes so far announced.
    pending_.store(false);
    drain();
    return early;
  }

  // At the full rate the loop sleeps to deadlines and never waits here: a
  // command then costs no system call to announce (it is taken next period).
  void wake() override {
    pending_.store(true);
    if (!waiting_.load()) return;
    const std::uint64_t one = 1;
    // EAGAIN only when the counter is full: a wake is pending anyway.
    [[maybe_unused]] const ssize_t n = write(wake_fd_, &one, sizeof one);
  }

 private:
  void drain() {
    std::uint64_t count = 0;
    while (read(wake_fd_, &count, sizeof count) > 0) {}
  }

  int wake_fd_;
  std::atomic<bool> waiting_{false};  // in wait_until
  std::atomic<bool> pending_{false};  // woken since the last wait_until returned
  std::vector<pollfd> polled_;
};

}  // namespace

std::unique_ptr<LoopWaiter> make_poll_waiter() { return std::make_unique<PollWaiter>(); }

}  // namespace server
