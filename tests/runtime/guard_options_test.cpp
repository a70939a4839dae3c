// The options of the unlock code's guard and of connection management, on the
// command line and as TOML keys: what they accept and what they refuse.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "server/options.hpp"
#include "tests/support/temp_dir.hpp"

namespace {

std::expected<server::ParseOutcome, std::string> parse(std::vector<std::string> args) {
  args.insert(args.begin(), "homingd");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return server::parse_options(static_cast<int>(args.size()), argv.data());
}

}  // namespace

TEST_CASE("the unlock code option takes a 32-bit code and refuses 0 and anything larger") {
  auto p = parse({"--unlock-code", "4294967295"});
  REQUIRE(p);
  CHECK(p->options.unlock_code == 4294967295LL);
  p = parse({"--unlock-code", "4321"});
  REQUIRE(p);
  CHECK(p->options.unlock_code == 4321);
  for (const char* bad : {"0", "4294967296", "-1", "code"}) {
    INFO(bad);
    const auto refused = parse({"--unlock-code", bad});
    REQUIRE_FALSE(refused);
    CHECK(refused.error().find("--unlock-code") != std::string::npos);
  }
}

TEST_CASE("the unlock lockout defaults to 10 s doubling up to 900 s and its cap may not be below its start") {
  auto p = parse({});
  REQUIRE(p);
  CHECK(p->options.unlock_lockout_s == 10);
  CHECK(p->options.unlock_lockout_max_s == 900);
  CHECK(p->options.refusal_log_interval_s == 10);
  p = parse({"--unlock-lockout-s", "1", "--unlock-lockout-max-s", "2", "--refusal-log-interval-s", "1"});
  REQUIRE(p);
  CHECK(p->options.unlock_lockout_s == 1);
  CHECK(p->options.unlock_lockout_max_s == 2);
  const auto refused = parse({"--unlock-lockout-s", "60", "--unlock-lockout-max-s", "30"});
  REQUIRE_FALSE(refused);
  CHECK(refused.error().find("--unlock-lockout-max-s 30 is below --unlock-lockout-s 60") != std::string::npos);
  CHECK_FALSE(parse({"--unlock-lockout-s", "0"}));
}

TEST_CASE("the --privileged list takes IPv4 addresses and CIDR, --max-clients-per-address a count") {
  auto p = parse({"--privileged", "10.0.0.5,192.168.1.0/29", "--max-clients-per-address", "4"});
  REQUIRE(p);
  CHECK(p->options.privileged == std::vector<std::string>{"10.0.0.5", "192.168.1.0/29"});
  CHECK(p->options.max_clients_per_address == 4);
  CHECK(parse({})->options.max_clients_per_address == 0);
  const auto refused = parse({"--privileged", "10.0.0.5,hmi.local"});
  REQUIRE_FALSE(refused);
  CHECK(refused.error() == "--privileged: 'hmi.local' is not an IPv4 address or CIDR (e.g. 10.0.0.5 or 10.0.0.0/29)");
  CHECK_FALSE(parse({"--max-clients-per-address", "-1"}));
}

TEST_CASE("the guard's options are TOML keys too") {
  test_support::TempDir dir{"guard-options"};
  const std::string path = dir.file("homingd.toml");
  test_support::write_text(path, "privileged = [\"10.0.0.5\", \"10.0.1.0/24\"]\n"
                                 "max_clients_per_address = 3\n"
                                 "unlock_code = 3000000123\n"
                                 "unlock_lockout_s = 5\n"
                                 "unlock_lockout_max_s = 60\n"
                                 "refusal_log_interval_s = 30\n");
  const auto p = parse({"--config", path});
  REQUIRE(p);
  const server::Options& o = p->options;
  CHECK(o.privileged == std::vector<std::string>{"10.0.0.5", "10.0.1.0/24"});
  CHECK(o.max_clients_per_address == 3);
  CHECK(o.unlock_code == 3000000123LL);
  CHECK(o.unlock_lockout_s == 5);
  CHECK(o.unlock_lockout_max_s == 60);
  CHECK(o.refusal_log_interval_s == 30);
}
