// The machine's own floor for a periodic loop: a bare clock_nanosleep loop on
// absolute CLOCK_MONOTONIC deadlines (the same scheme and the same 1 µs
// lateness histogram as homingd's control loop), doing no work.
//
//   loop_floor --period-us 1000 --duration 3
//
// Prints "RESULT periods=... p50_us=... p99_us=... p999_us=... max_us=..." and
// the loop's own counters over its periods (bench::SelfCounters: CPU, context
// switches, run-queue wait), the reference run_benchmarks.py compares homingd's
// control thread with.
#include <time.h>

#include <cerrno>

#include "bench_util.hpp"

int main(int argc, char** argv) {
  bench::Args a(argc, argv, {{"period-us", "1000"}, {"duration", "3"}});
  const std::int64_t period_ns = a.num("period-us") * 1000;
  const std::int64_t end = bench::now_ns() + static_cast<std::int64_t>(a.real("duration") * 1e9);
  bench::LatenessHistogram h;
  std::uint64_t late_periods = 0;
  std::int64_t deadline = bench::now_ns() + period_ns;
  const bench::SelfCounters before = bench::SelfCounters::now();
  for (;;) {
    timespec ts{static_cast<time_t>(deadline / 1'000'000'000), static_cast<long>(deadline % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {}
    const std::int64_t now = bench::now_ns();
    h.add((now - deadline) / 1000.0);
    if (now - deadline > period_ns) ++late_periods;
    if (now >= end) break;
    deadline += period_ns;
    if (now - deadline > period_ns) deadline = now + period_ns;  // far behind: do not burst (as homingd)
  }
  const std::string counters = bench::SelfCounters::now().since(before);
  std::printf("loop_floor: %llu periods of %lld us: lateness p50 %.0f us p99 %.0f us p99.9 %.0f us max %.0f us\n",
              (unsigned long long)h.total, (long long)(period_ns / 1000), h.percentile_us(0.5), h.percentile_us(0.99),
              h.percentile_us(0.999), h.max_us);
  std::printf("RESULT periods=%llu late_periods=%llu p50_us=%.0f p99_us=%.0f p999_us=%.0f max_us=%.0f%s\n",
              (unsigned long long)h.total, (unsigned long long)late_periods, h.percentile_us(0.5),
              h.percentile_us(0.99), h.percentile_us(0.999), h.max_us, counters.c_str());
  return 0;
}
