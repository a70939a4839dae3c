// A housekeeping step that fails at every look is logged when it starts
// failing, then at most once a minute, and once when it works again.
#include <catch2/catch.hpp>

#include <memory>
#include <string>
#include <vector>

#include "server/recurring_warning.hpp"
#include "tests/support/captured_log.hpp"

namespace {

struct Lines : test_support::CapturedLog {
  std::vector<std::string> all() const { return lines(); }
};

}  // namespace

TEST_CASE("a backup that fails twice a second for two minutes on a full disk is three warnings and one line when it "
          "works again") {
  Lines log;
  server::RecurringWarning w("settings backup not written", "settings backup written again");
  w.worked(0);  // working all along: nothing to say
  CHECK(log.all().empty());
  std::int64_t t = 1000;
  for (; t < 1000 + 125'000; t += 500) w.failed(t, "database or disk is full");
  CHECK(w.failing());
  auto lines = log.all();
  REQUIRE(lines.size() == 3);  // at 1 s, 61 s and 121 s
  CHECK(lines[0].find("settings backup not written: database or disk is full") != std::string::npos);
  CHECK(lines[1].find("still failing: 121 attempts in 60 s") != std::string::npos);
  CHECK(lines[2].find("still failing: 241 attempts in 120 s") != std::string::npos);
  w.worked(t);
  lines = log.all();
  REQUIRE(lines.size() == 4);
  CHECK(lines[3].find("settings backup written again after 250 failed attempts in 125 s") != std::string::npos);
  CHECK_FALSE(w.failing());
  w.worked(t + 500);
  CHECK(log.all().size() == 4);
}

TEST_CASE("a recurring warning whose reason changes says the new reason at once") {
  Lines log;
  server::RecurringWarning w("settings backup not written", "settings backup written again");
  w.failed(0, "database or disk is full");
  w.failed(500, "database or disk is full");
  w.failed(1000, "permission denied");
  const auto lines = log.all();
  REQUIRE(lines.size() == 2);
  CHECK(lines[1].find("permission denied (still failing: 3 attempts in 1 s)") != std::string::npos);
}
