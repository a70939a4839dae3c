// How long a TCP event loop polls before it sleeps (server/poll_window.hpp):
// the window learns from how long the loop waited for its next request.
#include <catch2/catch.hpp>

#include "server/poll_window.hpp"

using namespace std::chrono_literals;
using server::PollWindow;

TEST_CASE("a loop whose client sends its next request soon after each answer polls up to the longest window") {
  PollWindow poll(100us);
  CHECK(poll.window() == 0us);  // a new loop sleeps at once
  for (const auto expected : {10us, 20us, 40us, 80us, 100us, 100us}) {
    poll.waited(100us, false);  // the request came after the window but within the longest
    CHECK(poll.window() == expected);
  }
  poll.waited(30us, true);  // caught while polling: the window stays
  CHECK(poll.window() == 100us);
}

TEST_CASE("a loop whose client polls every 100 ms stops polling after a few waits") {
  PollWindow poll(100us);
  for (int i = 0; i < 5; ++i) poll.waited(100us, false);
  REQUIRE(poll.window() == 100us);
  for (const auto expected : {50us, 25us, 12us, 0us, 0us}) {
    poll.waited(100ms, false);
    CHECK(poll.window() == expected);
  }
}

TEST_CASE("a request that comes later than the longest window never starts polling") {
  PollWindow poll(100us);
  poll.waited(101us, false);
  CHECK(poll.window() == 0us);
  poll.waited(1s, false);
  CHECK(poll.window() == 0us);
}

TEST_CASE("a loop told to poll 0 us never polls") {
  PollWindow poll(0us);
  for (int i = 0; i < 3; ++i) poll.waited(1us, false);
  CHECK(poll.window() == 0us);
}

TEST_CASE("a longest window shorter than the first step is the whole window") {
  PollWindow poll(5us);
  poll.waited(3us, false);
  CHECK(poll.window() == 5us);
}
