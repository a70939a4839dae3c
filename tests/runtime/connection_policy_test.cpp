// Who gets a connection when the server is full (server/connection_policy.hpp):
// the choice alone, on the connections a server would hold.
#include <catch2/catch.hpp>

#include <vector>

#include "server/connection_policy.hpp"

using server::Admission;
using server::ConnectionLimits;
using server::HeldConnection;
using server::Peer;

namespace {

constexpr std::uint32_t kHog = 0x7F000002;   // 127.0.0.2
constexpr std::uint32_t kHmi = 0x7F000003;   // 127.0.0.3, privileged
constexpr std::uint32_t kOther = 0x7F000004; // 127.0.0.4

// n connections of one address, the first the least recently active unless `recent` says otherwise.
std::vector<HeldConnection> from(std::uint32_t ip, int n, bool privileged = false, std::int64_t t0 = 100) {
  std::vector<HeldConnection> held;
  for (int i = 0; i < n; ++i) held.push_back({{ip, privileged}, t0 + i});
  return held;
}

}  // namespace

TEST_CASE("with room left a client is admitted and nothing is closed") {
  const auto held = from(kHog, 3);
  const Admission a = server::admit(held, {kOther, false}, {4, 0});
  CHECK(a.kind == Admission::Kind::admit);
}

TEST_CASE("one address holding every connection gives way to an ordinary client: its least recently active closes") {
  auto held = from(kHog, 32);
  held[17].last_active_ns = 5;  // polled least recently
  const Admission a = server::admit(held, {kOther, false}, {32, 0});
  REQUIRE(a.kind == Admission::Kind::admit_closing);
  CHECK(a.close == 17);
}

TEST_CASE("a privileged client displaces the least recently active connection that is not privileged") {
  auto held = from(kOther, 2, true, 1);  // privileged, and the least recently active of all
  const auto hog = from(kHog, 2, false, 50);
  held.insert(held.end(), hog.begin(), hog.end());
  const Admission a = server::admit(held, {kHmi, true}, {4, 0});
  REQUIRE(a.kind == Admission::Kind::admit_closing);
  CHECK(a.close == 2);  // the hog's older one, not a privileged one
}

TEST_CASE("an address that fills the server is refused its next connection rather than closing its own") {
  const auto held = from(kHog, 4);
  CHECK(server::admit(held, {kHog, false}, {4, 0}).kind == Admission::Kind::refuse_full);
}

TEST_CASE("a full server of one connection per address does not churn: an ordinary client is refused") {
  std::vector<HeldConnection> held;
  for (std::uint32_t i = 0; i < 4; ++i) held.push_back({{0x0A000001 + i, false}, 10 + i});
  CHECK(server::admit(held, {kOther, false}, {4, 0}).kind == Admission::Kind::refuse_full);
  // ...but the HMI still gets in.
  const Admission a = server::admit(held, {kHmi, true}, {4, 0});
  REQUIRE(a.kind == Admission::Kind::admit_closing);
  CHECK(a.close == 0);
}

TEST_CASE("an address gives way only when it holds at least two more connections than the newcomer's") {
  auto held = from(kHog, 2);
  const auto other = from(kOther, 1, false, 1);
  held.insert(held.end(), other.begin(), other.end());
  // kOther (1) asks for a second: kHog holds 2, not 3: refused.
  CHECK(server::admit(held, {kOther, false}, {3, 0}).kind == Admission::Kind::refuse_full);
  // A third address (0) may take one of kHog's (2 >= 0 + 2): its least recently active.
  const Admission a = server::admit(held, {kHmi, false}, {3, 0});
  REQUIRE(a.kind == Admission::Kind::admit_closing);
  CHECK(a.close == 0);
}

TEST_CASE("the cap per address refuses a further connection of that address even with room left") {
  const auto held = from(kHog, 2);
  const Admission a = server::admit(held, {kHog, false}, {32, 2});
  CHECK(a.kind == Admission::Kind::refuse_address_cap);
  CHECK(a.address_count == 2);
  CHECK(server::admit(held, {kOther, false}, {32, 2}).kind == Admission::Kind::admit);
}

TEST_CASE("a server full of privileged connections refuses even a privileged client") {
  const auto held = from(kHmi, 3, true);
  CHECK(server::admit(held, {kOther, true}, {3, 0}).kind == Admission::Kind::refuse_full);
}
