// homingd --config FILE: the TOML file read by toml++ (server/config_file.hpp)
// as the long options it names, the command line winning; every mistake in
// the file refused with the file's name and what is wrong.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "server/options.hpp"
#include "tests/support/temp_dir.hpp"

namespace {

std::expected<server::ParseOutcome, std::string> parse_with(const std::string& config_text,
                                                            std::vector<std::string> args = {}) {
  test_support::TempDir dir{"config-test"};
  const std::string path = dir.file("homingd.toml");
  test_support::write_text(path, config_text);
  args.insert(args.begin(), {"homingd", "--config", path});
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return server::parse_options(static_cast<int>(args.size()), argv.data());
}

}  // namespace

TEST_CASE("config file values of every TOML kind reach their options") {
  const auto parsed = parse_with("unit = 7\n"
                                 "time_scale = 2.5\n"
                                 "parity = \"O\"\n"
                                 "no_tcp = true\n"
                                 "rtu = \"/dev/ttyUSB1\"\n"
                                 "write-allow = [\"10.0.0.0/8\", \"192.168.1.7\"]\n");
  REQUIRE(parsed);
  const server::Options& o = parsed->options;
  CHECK(o.unit_id == 7);
  CHECK(o.time_scale == 2.5);
  CHECK(o.parity == 'O');
  CHECK_FALSE(o.tcp_enabled);
  CHECK(o.rtu_device == "/dev/ttyUSB1");
  CHECK(o.write_allow == std::vector<std::string>{"10.0.0.0/8", "192.168.1.7"});
}

TEST_CASE("the command line wins over the config file") {
  const auto parsed = parse_with("unit = 7\nlog_level = \"warn\"\n", {"--unit", "9"});
  REQUIRE(parsed);
  CHECK(parsed->options.unit_id == 9);
  CHECK(parsed->options.log_level == "warn");
}

TEST_CASE("the gpiod table of the config file is left to the GPIO backend") {
  const auto parsed = parse_with("unit = 4\n[gpiod]\nchip = \"gpiochip0\"\n[gpiod.axes.X]\nstep = 23\n");
  REQUIRE(parsed);
  CHECK(parsed->options.unit_id == 4);
}

TEST_CASE("a config file that is not TOML is refused with its name and the line") {
  const auto parsed = parse_with("unit = 7\nparity = \"E\n");
  REQUIRE_FALSE(parsed);
  CHECK_THAT(parsed.error(), Catch::StartsWith("--config ") && Catch::Contains("homingd.toml: line 2:"));
}

TEST_CASE("an unknown key in the config file is refused by name, not ignored") {
  const auto parsed = parse_with("unit = 7\nbaudrate = 9600\n");
  REQUIRE_FALSE(parsed);
  CHECK_THAT(parsed.error(), Catch::Contains("homingd.toml: unknown key 'baudrate'"));
}

TEST_CASE("a config file cannot name the config help or version options") {
  for (const char* key : {"config = \"other.toml\"", "help = true", "version = true"}) {
    const auto parsed = parse_with(std::string(key) + "\n");
    REQUIRE_FALSE(parsed);
    CHECK_THAT(parsed.error(), Catch::Contains("unknown key"));
  }
}

TEST_CASE("a config file section other than gpiod is refused") {
  const auto parsed = parse_with("[modbus]\nunit = 3\n");
  REQUIRE_FALSE(parsed);
  CHECK_THAT(parsed.error(), Catch::Contains("unknown section [modbus] (known: [gpiod])"));
}

TEST_CASE("config file values no option takes are refused naming the key") {
  for (const char* text : {"time_scale = nan\n", "time_scale = inf\n", "rtu = 1979-05-27\n",
                           "write_allow = [[\"10.0.0.1\"]]\n", "unit = { value = 3 }\n"}) {
    const auto parsed = parse_with(text);
    INFO(text);
    REQUIRE_FALSE(parsed);
    CHECK_THAT(parsed.error(), Catch::Contains("key '"));
  }
}

TEST_CASE("a wrong value in the config file is refused naming the option and what it takes") {
  const auto parsed = parse_with("parity = \"X\"\n");
  REQUIRE_FALSE(parsed);
  CHECK_THAT(parsed.error(), Catch::Contains("--parity") && Catch::Contains("N,E,O"));
}

TEST_CASE("a listening address in the config file that is a host name is refused naming the option") {
  // libmodbus would listen on 255.255.255.255 for it, where no client reaches.
  const auto parsed = parse_with("tcp = \"cabinet-7:502\"\n");
  REQUIRE_FALSE(parsed);
  CHECK_THAT(parsed.error(), Catch::Contains("--tcp: 'cabinet-7' is not an IPv4 address to listen on"));
  CHECK(parse_with("tcp = \"0.0.0.0:502\"\n"));
}

TEST_CASE("a config file that does not exist is refused naming it, not an abort") {
  std::vector<std::string> args{"homingd", "--config", "/nonexistent/homingd.toml"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const auto parsed = server::parse_options(static_cast<int>(args.size()), argv.data());
  REQUIRE_FALSE(parsed);
  CHECK_THAT(parsed.error(), Catch::Contains("--config") && Catch::Contains("/nonexistent/homingd.toml") &&
                                 Catch::Contains("does not exist"));
}
