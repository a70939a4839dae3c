#include "event_clock.hpp"

#include <sys/utsname.h>

#include <charconv>
#include <cstdlib>

namespace homing::gpiod {

EventClock expected_event_clock(std::string_view release) {
  int major = 0, minor = 0;
  const char* p = release.data();
  const char* end = release.data() + release.size();
  auto r = std::from_chars(p, end, major);
  if (r.ec != std::errc{} || r.ptr == end || *r.ptr != '.') return EventClock::monotonic;
  r = std::from_chars(r.ptr + 1, end, minor);
  if (r.ec != std::errc{}) return EventClock::monotonic;
  return (major < 5 || (major == 5 && minor < 7)) ? EventClock::realtime : EventClock::monotonic;
}

EventClock running_kernel_event_clock() {
  utsname u{};
  if (uname(&u) != 0) return EventClock::monotonic;
  return expected_event_clock(u.release);
}

EventClock classify_timestamp(std::int64_t ts, std::int64_t now_mono, std::int64_t now_real) {
  return std::llabs(now_real - ts) < std::llabs(now_mono - ts) ? EventClock::realtime : EventClock::monotonic;
}

std::int64_t to_monotonic_ns(std::int64_t ts, std::int64_t now_mono, std::int64_t now_real) {
  if (classify_timestamp(ts, now_mono, now_real) == EventClock::monotonic) return ts;
  return ts - (now_real - now_mono);
}

}  // namespace homing::gpiod
