// FC 43 / 14 (Read Device Identification): the basic and regular objects.
#include <catch2/catch.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "server/device_identification.hpp"

namespace {

// The objects of a reply: id -> text, in order.
std::vector<std::pair<int, std::string>> objects_of(const server::Reply& r) {
  std::vector<std::pair<int, std::string>> out;
  REQUIRE(r.pdu.size() >= 7);
  std::size_t at = 7;
  for (int n = 0; n < r.pdu[6]; ++n) {
    REQUIRE(at + 2 <= r.pdu.size());
    const int id = r.pdu[at];
    const std::size_t len = r.pdu[at + 1];
    REQUIRE(at + 2 + len <= r.pdu.size());
    out.emplace_back(id, std::string(r.pdu.begin() + static_cast<long>(at + 2), r.pdu.begin() + static_cast<long>(at + 2 + len)));
    at += 2 + len;
  }
  CHECK(at == r.pdu.size());
  return out;
}

}  // namespace

TEST_CASE("a vendor URL not configured is not among the regular objects and its individual read is exception 02") {
  const server::DeviceIdentity identity;  // no --vendor-url
  const auto regular = objects_of(server::device_identification({2, 0}, identity));
  REQUIRE(regular.size() == 6);
  CHECK(regular[0] == std::pair<int, std::string>{0, "Homing Module Works"});
  CHECK(regular[3].first == 4);  // 3 is absent, not empty
  CHECK(regular[5].first == 6);
  CHECK(server::device_identification({4, 3}, identity).pdu == std::vector<std::uint8_t>{0xAB, 0x02});
  // Configured: there, in its place.
  server::DeviceIdentity with_url;
  with_url.vendor_url = "https://example.com/hm6";
  const auto all = objects_of(server::device_identification({2, 0}, with_url));
  REQUIRE(all.size() == 7);
  CHECK(all[3] == std::pair<int, std::string>{3, "https://example.com/hm6"});
  CHECK(objects_of(server::device_identification({4, 3}, with_url)) ==
        std::vector<std::pair<int, std::string>>{{3, "https://example.com/hm6"}});
  // The basic objects are always there, and a stream from an absent object goes on with the next.
  CHECK(objects_of(server::device_identification({1, 0}, identity)).size() == 3);
  const auto from3 = objects_of(server::device_identification({2, 3}, identity));
  REQUIRE_FALSE(from3.empty());
  CHECK(from3.front().first == 4);
}
