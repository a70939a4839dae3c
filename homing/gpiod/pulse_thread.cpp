#include "pulse_thread.hpp"

#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <cerrno>
#include <cstring>
#include <fmt/format.h>

namespace homing::gpiod {
namespace {

std::int64_t clock_ns(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

std::int64_t monotonic_now_ns() { return clock_ns(CLOCK_MONOTONIC); }
std::int64_t realtime_now_ns() { return clock_ns(CLOCK_REALTIME); }

PulseThread::PulseThread(std::vector<StepGenerator*> generators, std::int64_t tick_ns, int rt_priority)
    : generators_(std::move(generators)), tick_ns_(tick_ns), rt_priority_(rt_priority) {}

PulseThread::~PulseThread() { stop(); }

std::string PulseThread::start() {
  if (thread_.joinable()) return {};
  stop_ = false;
  thread_ = std::thread([this] { run(); });
  if (rt_priority_ <= 0) return {};
  sched_param p{};
  p.sched_priority = rt_priority_;
  if (const int err = pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &p); err != 0)
    return fmt::format("gpiod: pulse thread stays at normal priority (SCHED_FIFO {} refused: {}); "
                       "grant CAP_SYS_NICE or an rtprio limit for steadier pulses",
                       rt_priority_, std::strerror(err));
  return {};
}

void PulseThread::stop() {
  stop_ = true;
  wake();
  if (thread_.joinable()) thread_.join();
}

void PulseThread::wake() {
  wakes_.fetch_add(1);
  wakes_.notify_one();
}

void PulseThread::run() {
  std::int64_t deadline = monotonic_now_ns() + tick_ns_;
  while (!stop_) {
    timespec ts{static_cast<time_t>(deadline / 1'000'000'000), static_cast<long>(deadline % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {}
    // Read before the ticks: a segment pushed after them changes it, so the
    // sleep below cannot miss it.
    const std::uint64_t seen = wakes_.load();
    const std::int64_t now = monotonic_now_ns();
    bool all_resting = true;
    for (StepGenerator* g : generators_) {
      g->tick(now);
      all_resting = all_resting && g->resting();
    }
    turns_.fetch_add(1);
    deadline += tick_ns_;
    if (now - deadline > tick_ns_) deadline = now + tick_ns_;  // far behind: no burst of ticks
    if (all_resting && !stop_) {
      wakes_.wait(seen);
      deadline = monotonic_now_ns() + tick_ns_;
    }
  }
}

}  // namespace homing::gpiod
