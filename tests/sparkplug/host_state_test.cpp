// The primary host's STATE message as Sparkplug 3.0 defines it, and what the
// edge node makes of a sequence of them.
#include <catch2/catch.hpp>

#include "sparkplug/host_state.hpp"

using sparkplug::HostState;
using sparkplug::parse_host_state;

TEST_CASE("a STATE payload is JSON with a boolean online and an integer timestamp") {
  const auto s = parse_host_state(R"({"online": true, "timestamp": 1700000000123})");
  REQUIRE(s);
  CHECK(s->online);
  CHECK(s->timestamp == 1700000000123u);
  CHECK(sparkplug::state_topic("scada-1") == "spBv1.0/STATE/scada-1");
}

TEST_CASE("a payload that is not a STATE message is refused, not taken as offline or online") {
  CHECK_FALSE(parse_host_state("ONLINE"));  // Sparkplug 2.2's plain text is not 3.0's STATE
  CHECK_FALSE(parse_host_state(R"({"online": "yes", "timestamp": 1})"));
  CHECK_FALSE(parse_host_state(R"({"online": true})"));
  CHECK_FALSE(parse_host_state(R"({"online": true, "timestamp": -5})"));
  CHECK_FALSE(parse_host_state(R"([true, 1])"));
  CHECK_FALSE(parse_host_state(""));
}

TEST_CASE("the primary host is online from an online STATE until a newer offline one") {
  sparkplug::PrimaryHost host;
  CHECK_FALSE(host.online());
  CHECK(host.take(HostState{true, 100}));
  CHECK(host.online());
  CHECK_FALSE(host.take(HostState{false, 99}));  // stale: older than the state taken
  CHECK(host.online());
  CHECK(host.take(HostState{false, 101}));
  CHECK_FALSE(host.online());
  host.take(HostState{true, 102});
  host.forget();  // a new session waits for the host again
  CHECK_FALSE(host.online());
  CHECK(host.take(HostState{true, 102}));  // the retained message of the new session
}
