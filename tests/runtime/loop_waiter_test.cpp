// The control thread's real waiter (server/loop_waiter.hpp): a quiet wait
// ends on a wake, given before it or during it, and on a readable
// descriptor; a sleep to a deadline is not ended by a wake. Deadlines far
// off or already passed: nothing here depends on how fast the machine is.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <array>
#include <atomic>
#include <thread>

#include "server/loop_waiter.hpp"

namespace {

constexpr std::int64_t kHourNs = 3600LL * 1'000'000'000;

struct Pipe {
  std::array<int, 2> fd{-1, -1};
  Pipe() { REQUIRE(pipe(fd.data()) == 0); }
  ~Pipe() {
    close(fd[0]);
    close(fd[1]);
  }
};

}  // namespace

TEST_CASE("a wake given before a quiet wait ends it at once, and only that wait") {
  auto w = server::make_poll_waiter();
  w->wake();
  CHECK(w->wait_until(w->now_ns() + kHourNs, {}));
  // Drained: the next wait runs to its deadline (one already passed here).
  CHECK_FALSE(w->wait_until(w->now_ns() - 1, {}));
}

TEST_CASE("a wake from another thread ends a quiet wait under way") {
  auto w = server::make_poll_waiter();
  std::thread waker([&] { w->wake(); });
  CHECK(w->wait_until(w->now_ns() + kHourNs, {}));
  waker.join();
}

TEST_CASE("a readable descriptor ends a quiet wait, and a quiet one without it runs to its deadline") {
  auto w = server::make_poll_waiter();
  Pipe p;
  const int fds[] = {p.fd[0]};
  CHECK_FALSE(w->wait_until(w->now_ns() + 2'000'000, fds));
  REQUIRE(write(p.fd[1], "x", 1) == 1);
  CHECK(w->wait_until(w->now_ns() + kHourNs, fds));
}

TEST_CASE("a sleep to a deadline is not ended by a wake, and leaves the wake for the next quiet wait") {
  auto w = server::make_poll_waiter();
  w->wake();
  const std::int64_t deadline = w->now_ns() + 2'000'000;
  w->sleep_until(deadline);
  CHECK(w->now_ns() >= deadline);
  CHECK(w->wait_until(w->now_ns() + kHourNs, {}));
}

TEST_CASE("no wake is lost when wakes race the start and the end of quiet waits") {
  // The waker fires whenever the waiter is about to wait or has just woken:
  // a lost wake leaves a wait running to its (short, bounded) deadline.
  auto w = server::make_poll_waiter();
  constexpr int kRounds = 2000;
  std::atomic<int> asked{0};
  std::atomic<bool> done{false};
  std::thread waker([&] {
    int given = 0;
    while (!done.load() && given < kRounds) {
      if (asked.load() > given) {
        ++given;
        w->wake();
      }
    }
  });
  int ended_by_wake = 0;
  for (int i = 0; i < kRounds; ++i) {
    asked.store(i + 1);
    if (w->wait_until(w->now_ns() + 2'000'000'000LL, {})) ++ended_by_wake;
  }
  done.store(true);
  waker.join();
  CHECK(ended_by_wake == kRounds);
}
