// server::OptionParser used more than once (the config fuzzer parses one
// command line per input with one parser): each parse starts from the
// defaults, whatever the one before set or refused.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "server/options.hpp"

namespace {

std::expected<server::ParseOutcome, std::string> parse(server::OptionParser& parser, std::vector<std::string> args) {
  args.insert(args.begin(), "homingd");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return parser.parse(static_cast<int>(args.size()), argv.data());
}

}  // namespace

TEST_CASE("a reused option parser starts every command line from the defaults") {
  server::OptionParser parser;
  const auto first = parse(parser, {"--unit", "5", "--rtu", "/dev/ttyUSB0", "--no-tcp", "--parity", "O",
                                    "--word-order", "low-first", "--write-allow", "10.0.0.0/8,192.168.1.7"});
  REQUIRE(first);
  CHECK(first->options.unit_id == 5);
  CHECK(first->options.rtu_device == "/dev/ttyUSB0");
  CHECK_FALSE(first->options.tcp_enabled);
  CHECK(first->options.parity == 'O');
  CHECK(first->options.word_order == registers::WordOrder::low_first);
  CHECK(first->options.write_allow.size() == 2);

  const auto second = parse(parser, {});
  REQUIRE(second);
  const server::Options defaults;
  CHECK(second->options.unit_id == defaults.unit_id);
  CHECK(second->options.rtu_device.empty());
  CHECK(second->options.tcp_enabled);
  CHECK(second->options.tcp_host == defaults.tcp_host);
  CHECK(second->options.tcp_port == defaults.tcp_port);
  CHECK(second->options.parity == defaults.parity);
  CHECK(second->options.word_order == defaults.word_order);
  CHECK(second->options.write_allow.empty());
}

TEST_CASE("a reused option parser forgets a refused command line") {
  server::OptionParser parser;
  const auto refused = parse(parser, {"--unit", "9", "--baud", "12345"});
  REQUIRE_FALSE(refused);
  CHECK(refused.error().find("baud") != std::string::npos);
  const auto next = parse(parser, {"--baud", "9600"});
  REQUIRE(next);
  CHECK(next->options.baud == 9600);
  CHECK(next->options.unit_id == server::Options{}.unit_id);
}
