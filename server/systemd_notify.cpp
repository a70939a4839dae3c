#include "systemd_notify.hpp"
#include "thread_name.hpp"

#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <chrono>
#include <cstdlib>
#include <cstring>

namespace server {

SystemdNotifier::SystemdNotifier(std::function<std::uint64_t()> progress) : progress_(std::move(progress)) {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  under_systemd_ = socket != nullptr && *socket != '\0';
  std::uint64_t usec = 0;
  // > 0 only when WATCHDOG_USEC is set (and WATCHDOG_PID, if set, is ours).
  if (under_systemd_ && sd_watchdog_enabled(0, &usec) > 0) watchdog_usec_ = usec;
}

SystemdNotifier::~SystemdNotifier() { stop_feeding(); }

void SystemdNotifier::ready(const std::string& status) {
  if (!under_systemd_) return;
  const std::string message = "READY=1\nSTATUS=" + status;
  if (const int rc = sd_notify(0, message.c_str()); rc < 0)
    spdlog::warn("systemd: READY=1 not delivered to NOTIFY_SOCKET ({}); systemd will time the start out",
                 std::strerror(-rc));
  if (watchdog_usec_ > 0 && !feeder_.joinable()) {
    spdlog::info("systemd: watchdog every {} ms, fed while the control loop runs", watchdog_usec_ / 2000);
    feeder_ = std::thread([this] {
      name_this_thread("sd-watchdog");
      feed_while_running();
    });
  }
}

void SystemdNotifier::stopping() {
  stop_feeding();
  if (under_systemd_) (void)sd_notify(0, "STOPPING=1\nSTATUS=stopping motion and shutting down");
}

void SystemdNotifier::stop_feeding() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (feeder_.joinable()) feeder_.join();
}

void SystemdNotifier::feed_while_running() {
  const auto interval = std::chrono::microseconds(watchdog_usec_ / 2);
  std::uint64_t last = progress_();
  bool stalled = false;
  std::unique_lock lock(mutex_);
  while (!wake_.wait_for(lock, interval, [this] { return stop_; })) {
    const std::uint64_t now = progress_();
    if (now != last) {
      (void)sd_notify(0, "WATCHDOG=1");
      if (stalled) spdlog::warn("systemd: the control loop runs again; watchdog fed");
      stalled = false;
    } else if (!stalled) {
      spdlog::error("systemd: the control loop ran no period for {} ms; the watchdog is not fed and systemd "
                    "will restart homingd if it stays so",
                    watchdog_usec_ / 2000);
      stalled = true;
    }
    last = now;
  }
}

}  // namespace server
