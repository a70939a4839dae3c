// The unlock code against guessing, as an attacker on the network meets it:
// thousands of codes written to the real homingd get nowhere (after 5 wrong
// codes in a row every unlock is refused for a while, the code not even
// tried), the right code written during the lockout is refused too, and
// works once the lockout has passed. The log holds counts per client and
// reason, not a line per refused write. Short lockouts (--unlock-lockout-s 1)
// keep the waits short; every wait is on something the module shows.
#include <catch2/catch.hpp>

#include <regex>

#include "daemon.hpp"
#include "registers/errors.hpp"

using namespace e2e;
using registers::RefusalReason;

namespace {

constexpr std::int64_t kCode = 3'000'000'123LL;  // needs both words: security.unlock32

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Refusals of one reason the log accounts for: lines written out whole plus
// the counts of the summary lines.
std::int64_t refusals_logged(const std::string& log, std::int64_t reason_code, const std::string& reason_name) {
  const std::string reason = "reason " + std::to_string(reason_code) + " (" + reason_name + ")";
  auto n = static_cast<std::int64_t>(count_of(log, ", " + reason + " at address"));
  const std::regex summary("(\\d+) more writes refused, " + std::regex_replace(reason, std::regex("[()]"), "\\$&"));
  for (std::sregex_iterator it(log.begin(), log.end(), summary), end; it != end; ++it) n += std::stoll((*it)[1]);
  return n;
}

}  // namespace

TEST_CASE("thousands of guessed unlock codes do not get in, and the right code works once the lockout has passed") {
  Daemon d({.extra = {"--unlock-code", std::to_string(kCode), "--unlock-lockout-s", "1", "--unlock-lockout-max-s", "2",
                      "--refusal-log-interval-s", "1"}});
  Client c = Client::tcp(d.port());
  REQUIRE(c.read("status.settings_locked") == 1);

  // A guesser: 5000 codes as one 32-bit value (FC 16), 1000 more by FC 06.
  int accepted = 0, other_answers = 0;
  std::int64_t locked_out = 0;  // answered "busy": refused as unlock_locked_out, each must be in the log
  const auto answer = [&](int r) {
    accepted += r == 0;
    locked_out += r == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY;
    other_answers += r != MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE && r != MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY && r != 0;
  };
  for (std::int64_t n = 1; n <= 5000; ++n) answer(c.write("security.unlock32", n));
  for (int n = 0; n < 1000; ++n) answer(c.write("security.unlock", (kCode & 0xFFFF) + n));
  CHECK(accepted == 0);
  CHECK(other_answers == 0);
  CHECK(c.read("status.settings_locked") == 1);
  CHECK(c.write("axis.x.seek_feedrate", 1200) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_FAILURE);  // still locked
  // Only the codes written outside a lockout were tried: 5, then one per lockout that passed.
  const std::int64_t tried = c.read("status.wrong_unlock_codes");
  std::printf("[unlock] 6000 codes written, %lld tried\n", static_cast<long long>(tried));
  CHECK(tried >= 5);
  CHECK(tried < 600);

  // The right code during a lockout is refused as unlock_locked_out: a
  // lockout seen before and after the write held during it (nothing but a
  // tried wrong code starts one).
  bool during = false;
  for (int attempt = 0; attempt < 20 && !during; ++attempt) {
    if (c.read("status.unlock_lockout_s") == 0) {
      REQUIRE(c.write("security.unlock32", 7) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);  // starts one
      continue;
    }
    const int r = c.write("security.unlock32", kCode);
    locked_out += r == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY;
    if (c.read("status.unlock_lockout_s") == 0) {
      if (r == 0) REQUIRE(c.write("cmd.lock_settings", 1) == 0);  // it had passed: lock again, try again
      continue;
    }
    during = true;
    CHECK(r == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
    CHECK(c.read("status.last_refusal_reason") == static_cast<int>(RefusalReason::unlock_locked_out));
    CHECK(c.read("status.settings_locked") == 1);
  }
  REQUIRE(during);

  // Once the lockout has passed, the right code works.
  REQUIRE(wait_until([&] { return c.read("status.unlock_lockout_s") == 0; }, 10s, 50ms));
  CHECK(c.write("security.unlock32", kCode) == 0);
  CHECK(c.read("status.settings_locked") == 0);
  CHECK(c.read("status.wrong_unlock_codes") == 0);
  CHECK(c.write("axis.x.seek_feedrate", 1200) == 0);

  // The log: the lockout announced with its count; thousands of refusals
  // accounted for in a few lines. The counts of an interval are written when
  // it ends, so wait for all of them rather than for the first line.
  const std::string reason = std::string(homing::name_of(RefusalReason::unlock_locked_out));
  const std::int64_t code = static_cast<std::int64_t>(RefusalReason::unlock_locked_out);
  std::printf("[unlock] %lld writes refused as %s\n", static_cast<long long>(locked_out), reason.c_str());
  REQUIRE(locked_out > 100);
  wait_until([&] { return refusals_logged(d.log(), code, reason) >= locked_out; }, 10s, 100ms);
  const std::string log = d.log();
  INFO(log.substr(0, 4000));
  CHECK(refusals_logged(log, code, reason) == locked_out);
  CHECK(log.find("5 wrong unlock codes in a row, the last from tcp 127.0.0.1:") != std::string::npos);
  CHECK(count_of(log, "write refused with exception") < 40);
  CHECK(count_of(log, "more writes refused, reason " + std::to_string(code) + " (" + reason + ")") >= 1);
}

TEST_CASE("a flood of refused writes is logged as counts per client and reason per interval, not a line per write") {
  Daemon d({.extra = {"--refusal-log-interval-s", "1"}});
  Client c = Client::tcp(d.port());
  constexpr int kWrites = 2000;
  int refused = 0;
  for (int i = 0; i < kWrites; ++i) refused += c.write("axis.y.seek_feedrate", 65000) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  REQUIRE(refused == kWrites);
  CHECK(c.read("status.refusal_count") == kWrites);
  const std::int64_t code = static_cast<std::int64_t>(RefusalReason::out_of_range);
  // Every one accounted for once the interval's counts are out.
  REQUIRE(wait_until([&] { return refusals_logged(d.log(), code, "out_of_range") >= kWrites; }, 10s, 100ms));
  const std::string log = d.log();
  INFO(log.substr(0, 4000));
  CHECK(refusals_logged(log, code, "out_of_range") == kWrites);
  const std::size_t whole = count_of(log, "write refused with exception");
  const std::size_t summaries = count_of(log, "more writes refused");
  std::printf("[refusal log] %d refused writes: %zu whole lines, %zu count lines\n", kWrites, whole, summaries);
  CHECK(whole >= 1);
  CHECK(whole + summaries < 40);
  CHECK(log.find("tcp 127.0.0.1: ") != std::string::npos);  // counted per client address
}
