// Refused requests in the log without flooding it (server/refusal_log.hpp),
// with the time passed by hand.
#include <catch2/catch.hpp>

#include <chrono>
#include <string>
#include <vector>

#include "server/refusal_log.hpp"

using namespace std::chrono_literals;
using server::RefusalLog;
using Time = RefusalLog::Clock::time_point;

namespace {

struct Lines {
  std::vector<std::string> lines;
  RefusalLog log{"writes", 10s, [this](spdlog::level::level_enum, const std::string& l) { lines.push_back(l); }};
};

const std::string kReason = "reason 8 (wrong_unlock_code)";

}  // namespace

TEST_CASE("a flood of refusals of one client for one reason is one whole line, then one count per interval") {
  Lines l;
  Time t{};
  for (int i = 0; i < 1000; ++i) l.log.refused("tcp 10.0.0.9", kReason, spdlog::level::warn, "whole " + std::to_string(i), t + i * 1ms);
  REQUIRE(l.lines.size() == 1);
  CHECK(l.lines[0] == "whole 0");
  l.log.flush(t + 9s);
  CHECK(l.lines.size() == 1);  // the interval has not passed
  l.log.flush(t + 10s);
  REQUIRE(l.lines.size() == 2);
  CHECK(l.lines[1] == "tcp 10.0.0.9: 999 more writes refused, reason 8 (wrong_unlock_code), in the last 10 s "
                      "(one line per client and reason every 10 s)");
  // Still flooding in the next interval: counts only.
  for (int i = 0; i < 500; ++i) l.log.refused("tcp 10.0.0.9", kReason, spdlog::level::warn, "whole", t + 11s);
  l.log.flush(t + 20s);
  REQUIRE(l.lines.size() == 3);
  CHECK(l.lines[2].find(": 500 more writes refused") != std::string::npos);
}

TEST_CASE("refusals are counted apart per client and per reason") {
  Lines l;
  Time t{};
  for (int i = 0; i < 3; ++i) {
    l.log.refused("tcp 10.0.0.9", kReason, spdlog::level::warn, "a", t);
    l.log.refused("tcp 10.0.0.8", kReason, spdlog::level::warn, "b", t);
    l.log.refused("tcp 10.0.0.9", "reason 7 (locked)", spdlog::level::warn, "c", t);
  }
  CHECK(l.lines == std::vector<std::string>{"a", "b", "c"});
  l.log.flush(t + 10s);
  REQUIRE(l.lines.size() == 6);
  for (int i = 3; i < 6; ++i) CHECK(l.lines[i].find(": 2 more writes refused") != std::string::npos);
}

TEST_CASE("a client that was not refused for a whole interval is written out whole again") {
  Lines l;
  Time t{};
  l.log.refused("tcp 10.0.0.9", kReason, spdlog::level::warn, "first", t);
  l.log.flush(t + 10s);  // nothing counted: nothing written, the client forgotten
  CHECK(l.lines.size() == 1);
  l.log.refused("tcp 10.0.0.9", kReason, spdlog::level::warn, "again", t + 12s);
  CHECK(l.lines == std::vector<std::string>{"first", "again"});
}

TEST_CASE("on the way out the counts not yet written are written, the interval passed or not") {
  Lines l;
  Time t{};
  // The interval runs from the first look at the time (t + 1 s).
  for (int i = 0; i < 4; ++i) l.log.refused("tcp 10.0.0.9", kReason, spdlog::level::warn, "first", t + 1s);
  l.log.flush_all(t + 3s);
  REQUIRE(l.lines.size() == 2);
  CHECK(l.lines[1] == "tcp 10.0.0.9: 3 more writes refused, reason 8 (wrong_unlock_code), in the last 2 s "
                      "(one line per client and reason every 10 s)");
}
