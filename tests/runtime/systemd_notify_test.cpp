// server::SystemdNotifier against a notification socket the test owns: READY=1,
// WATCHDOG=1 only while the control loop's period counter moves, STOPPING=1.
#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <thread>

#include "server/systemd_notify.hpp"
#include "tests/server/notify_socket.hpp"

using namespace std::chrono_literals;
using notify_test::NotifySocket;
using notify_test::ScopedEnv;

namespace {

std::size_t count_line(const std::vector<std::string>& messages, const std::string& line) {
  return static_cast<std::size_t>(std::count_if(messages.begin(), messages.end(),
                                                [&](const std::string& m) { return NotifySocket::has_line(m, line); }));
}

// A control loop stand-in: advances its period counter while `running`.
struct FakeLoop {
  std::atomic<std::uint64_t> periods{0};
  std::atomic<bool> running{true};
  std::atomic<bool> quit{false};
  std::thread thread{[this] {
    while (!quit) {
      if (running) ++periods;
      std::this_thread::sleep_for(1ms);
    }
  }};
  ~FakeLoop() {
    quit = true;
    thread.join();
  }
};

}  // namespace

TEST_CASE("systemd notify: READY=1 with a status line, then WATCHDOG=1 again and again while the loop runs") {
  NotifySocket socket;
  ScopedEnv notify("NOTIFY_SOCKET", socket.path());
  ScopedEnv usec("WATCHDOG_USEC", "100000");
  ScopedEnv pid("WATCHDOG_PID", std::nullopt);
  FakeLoop loop;
  server::SystemdNotifier notifier([&] { return loop.periods.load(); });
  REQUIRE(notifier.under_systemd());
  REQUIRE(notifier.watchdog_usec() == 100000);

  notifier.ready("listening on tcp 127.0.0.1:1502");
  auto first = socket.receive(2s);
  REQUIRE(first);
  CHECK(NotifySocket::has_line(*first, "READY=1"));
  CHECK(NotifySocket::has_line(*first, "STATUS=listening on tcp 127.0.0.1:1502"));

  // Fed again and again (every 50 ms; how often is not timed here, a loaded
  // machine delays the feeder): five feeds come, and READY=1 only once.
  std::vector<std::string> messages;
  std::size_t feeds = 0;
  for (int i = 0; i < 50 && feeds < 5; ++i) {
    auto m = socket.receive(10s);
    if (!m) break;
    messages.push_back(*m);
    feeds = count_line(messages, "WATCHDOG=1");
  }
  CHECK(feeds == 5);
  CHECK(count_line(messages, "READY=1") == 0);
}

TEST_CASE("systemd notify: a control loop that runs no period stops the watchdog feed until it runs again") {
  NotifySocket socket;
  ScopedEnv notify("NOTIFY_SOCKET", socket.path());
  ScopedEnv usec("WATCHDOG_USEC", "100000");
  ScopedEnv pid("WATCHDOG_PID", std::nullopt);
  FakeLoop loop;
  server::SystemdNotifier notifier([&] { return loop.periods.load(); });
  notifier.ready("ok");
  REQUIRE(socket.wait_for("READY=1", 2s));
  REQUIRE(socket.wait_for("WATCHDOG=1", 2s));

  loop.running = false;
  (void)socket.collect(150ms);  // one feed may have been decided before the stall
  CHECK(count_line(socket.collect(500ms), "WATCHDOG=1") == 0);

  loop.running = true;
  CHECK(socket.wait_for("WATCHDOG=1", 1s));
}

TEST_CASE("systemd notify: STOPPING=1 on shutdown, and no WATCHDOG=1 after it") {
  NotifySocket socket;
  ScopedEnv notify("NOTIFY_SOCKET", socket.path());
  ScopedEnv usec("WATCHDOG_USEC", "100000");
  ScopedEnv pid("WATCHDOG_PID", std::nullopt);
  FakeLoop loop;
  server::SystemdNotifier notifier([&] { return loop.periods.load(); });
  notifier.ready("ok");
  REQUIRE(socket.wait_for("WATCHDOG=1", 2s));

  notifier.stopping();
  auto stopping = socket.wait_for("STOPPING=1", 2s);
  REQUIRE(stopping);
  CHECK(count_line(socket.collect(300ms), "WATCHDOG=1") == 0);
}

TEST_CASE("systemd notify: without NOTIFY_SOCKET nothing is sent and no watchdog is fed") {
  NotifySocket socket;  // exists, but nobody names it
  ScopedEnv notify("NOTIFY_SOCKET", std::nullopt);
  ScopedEnv usec("WATCHDOG_USEC", "100000");
  std::atomic<int> progress_reads{0};
  server::SystemdNotifier notifier([&] { return static_cast<std::uint64_t>(++progress_reads); });
  CHECK_FALSE(notifier.under_systemd());
  CHECK(notifier.watchdog_usec() == 0);
  notifier.ready("ok");
  CHECK(socket.collect(300ms).empty());
  CHECK(progress_reads == 0);
}

TEST_CASE("systemd notify: a WATCHDOG_PID of another process leaves the watchdog to that process") {
  NotifySocket socket;
  ScopedEnv notify("NOTIFY_SOCKET", socket.path());
  ScopedEnv usec("WATCHDOG_USEC", "100000");
  ScopedEnv pid("WATCHDOG_PID", std::to_string(::getpid() + 1));
  server::SystemdNotifier notifier([] { return std::uint64_t{0}; });
  CHECK(notifier.under_systemd());
  CHECK(notifier.watchdog_usec() == 0);
  notifier.ready("ok");
  CHECK(socket.wait_for("READY=1", 2s));
  CHECK(count_line(socket.collect(300ms), "WATCHDOG=1") == 0);
}
