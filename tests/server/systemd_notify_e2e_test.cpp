// homingd under a stand-in for systemd: NOTIFY_SOCKET points at a datagram
// socket this test owns, WATCHDOG_USEC asks for the watchdog (Type=notify,
// WatchdogSec= in packaging/homingd.service).
#include <catch2/catch.hpp>

#include <algorithm>

#include "daemon.hpp"
#include "notify_socket.hpp"

using namespace std::chrono_literals;
using notify_test::NotifySocket;
using notify_test::ScopedEnv;

TEST_CASE("homingd under systemd: READY=1 once it serves Modbus, WATCHDOG=1 while it runs, STOPPING=1 on SIGTERM") {
  NotifySocket socket;
  ScopedEnv notify("NOTIFY_SOCKET", socket.path());
  ScopedEnv usec("WATCHDOG_USEC", "200000");
  ScopedEnv pid("WATCHDOG_PID", std::nullopt);
  e2e::Daemon d;

  auto ready = socket.wait_for("READY=1", 10s);
  REQUIRE(ready);
  CHECK(NotifySocket::has_line(*ready, "STATUS=listening on tcp 127.0.0.1:" + std::to_string(d.port())));
  // Ready means served: a read right after READY=1 is answered.
  auto client = e2e::Client::tcp(d.port());
  REQUIRE(modbus_connect(client.ctx()) == 0);
  CHECK(client.try_read("status.state"));

  // Every 100 ms while the control loop runs.
  const auto fed = socket.collect(1000ms);
  const auto watchdogs = std::count_if(fed.begin(), fed.end(), [](const std::string& m) {
    return NotifySocket::has_line(m, "WATCHDOG=1");
  });
  CHECK(watchdogs >= 4);
  CHECK(watchdogs <= 12);
  CHECK(d.log().find("systemd: watchdog every 100 ms") != std::string::npos);

  const auto status = d.stop(SIGTERM, 15s);
  REQUIRE(status);
  CHECK(WIFEXITED(*status));
  CHECK(WEXITSTATUS(*status) == 0);
  CHECK(socket.wait_for("STOPPING=1", 2s));
}

TEST_CASE("homingd outside systemd: without NOTIFY_SOCKET it serves as before and feeds no watchdog") {
  ScopedEnv notify("NOTIFY_SOCKET", std::nullopt);
  ScopedEnv usec("WATCHDOG_USEC", "200000");
  e2e::Daemon d;
  auto client = e2e::Client::tcp(d.port());
  REQUIRE(modbus_connect(client.ctx()) == 0);
  CHECK(client.try_read("status.state"));
  std::this_thread::sleep_for(300ms);
  CHECK(d.log().find("systemd:") == std::string::npos);
}
