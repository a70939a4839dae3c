#pragma once
// systemd's service notification (Type=notify, WatchdogSec=): READY=1 once
// homingd serves, WATCHDOG=1 while its control loop runs, STOPPING=1 on the
// way out. Outside systemd (NOTIFY_SOCKET unset) every call does nothing.
//
// The watchdog is fed from a thread of its own, not from the control thread:
// libsystemd's sd_notify opens a socket and may block on a full queue, which
// a 1 ms real-time period must never wait for. The feeding thread sends
// WATCHDOG=1 only when the loop's period counter moved since the last one, so
// a control loop that hangs stops the feed and systemd restarts the service.
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace server {

class SystemdNotifier {
 public:
  // progress: a counter the control loop advances every period.
  explicit SystemdNotifier(std::function<std::uint64_t()> progress);
  ~SystemdNotifier();  // stops the feeding thread
  SystemdNotifier(const SystemdNotifier&) = delete;
  SystemdNotifier& operator=(const SystemdNotifier&) = delete;

  // READY=1 with a STATUS= line; starts feeding the watchdog when systemd
  // asked for one (WATCHDOG_USEC, every half of it).
  void ready(const std::string& status);
  // STOPPING=1; the watchdog is no longer fed.
  void stopping();

  bool under_systemd() const { return under_systemd_; }
  std::uint64_t watchdog_usec() const { return watchdog_usec_; }

 private:
  void feed_while_running();
  void stop_feeding();

  std::function<std::uint64_t()> progress_;
  bool under_systemd_ = false;
  std::uint64_t watchdog_usec_ = 0;  // 0: no watchdog asked for
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::thread feeder_;
};

}  // namespace server
