// Line-event timestamps: which clock the kernel used, and the mapping onto
// CLOCK_MONOTONIC (the runtime's clock).
#include <catch2/catch.hpp>

#include "homing/gpiod/event_clock.hpp"

using namespace homing::gpiod;

TEST_CASE("kernels before 5.7 stamp line events with CLOCK_REALTIME, later ones with CLOCK_MONOTONIC") {
  CHECK(expected_event_clock("4.19.0-26-amd64") == EventClock::realtime);
  CHECK(expected_event_clock("5.4.0-150-generic") == EventClock::realtime);
  CHECK(expected_event_clock("5.6.19") == EventClock::realtime);
  CHECK(expected_event_clock("5.7.0") == EventClock::monotonic);
  CHECK(expected_event_clock("5.10.0-28-arm64") == EventClock::monotonic);
  CHECK(expected_event_clock("6.1.0-rpi7-rpi-v8") == EventClock::monotonic);
  CHECK(expected_event_clock("garbage") == EventClock::monotonic);
}

TEST_CASE("a timestamp is classified by the clock it is near, and mapped onto CLOCK_MONOTONIC") {
  const std::int64_t mono = 12'345'000'000'000;           // 3.4 h of uptime
  const std::int64_t real = 1'700'000'000'000'000'000;    // 2023
  SECTION("monotonic stamp (kernel >= 5.7) is taken as it is") {
    const std::int64_t ts = mono - 300'000;
    CHECK(classify_timestamp(ts, mono, real) == EventClock::monotonic);
    CHECK(to_monotonic_ns(ts, mono, real) == ts);
  }
  SECTION("realtime stamp (kernel < 5.7 or a backport) keeps its distance to now") {
    const std::int64_t ts = real - 300'000;
    CHECK(classify_timestamp(ts, mono, real) == EventClock::realtime);
    CHECK(to_monotonic_ns(ts, mono, real) == mono - 300'000);
  }
}
