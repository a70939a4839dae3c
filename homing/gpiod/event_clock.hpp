#pragma once
// Line-event timestamps come from the kernel's event clock: CLOCK_REALTIME
// before Linux 5.7, CLOCK_MONOTONIC from 5.7 on (the v1 uAPI has no way to
// ask). The runtime works in CLOCK_MONOTONIC, so every timestamp is mapped
// onto it. The kernel version gives the expectation; each timestamp is also
// checked against both clocks, because vendor kernels backport the change.
#include <cstdint>
#include <string_view>

namespace homing::gpiod {

enum class EventClock : std::uint8_t { monotonic, realtime };

// From a uname release such as "5.4.0-150-generic" or "6.1.0-rpi7-rpi-v8".
EventClock expected_event_clock(std::string_view kernel_release);
EventClock running_kernel_event_clock();

// Which clock a timestamp was taken on: the one whose "now" it is nearer to.
// Realtime is ~1.7e18 ns (since 1970), monotonic is the uptime, so they are
// decades apart and one comparison decides.
EventClock classify_timestamp(std::int64_t ts_ns, std::int64_t now_monotonic_ns, std::int64_t now_realtime_ns);

// The timestamp on CLOCK_MONOTONIC. now_* are read together just before.
std::int64_t to_monotonic_ns(std::int64_t ts_ns, std::int64_t now_monotonic_ns, std::int64_t now_realtime_ns);

}  // namespace homing::gpiod
