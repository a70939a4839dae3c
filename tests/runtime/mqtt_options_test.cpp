// homingd's MQTT options: the scheme of --mqtt decides TLS and the default
// port; TLS files, user and password file go with it, and a mistake is
// refused at start naming the option.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "server/mqtt_node.hpp"
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

struct Files {
  test_support::TempDir dir;
  std::string ca = dir.file("ca.crt"), cert = dir.file("c.crt"), key = dir.file("c.key"), pw = dir.file("pw");
  Files() {
    for (const auto& f : {ca, cert, key}) test_support::write_text(f, "PEM");
    test_support::write_text(pw, "s3cret\nignored second line\n");
  }
};

}  // namespace

TEST_CASE("mqtt:// is plain MQTT on port 1883 unless a port is given") {
  auto r = parse({"--mqtt", "mqtt://broker.plant"});
  REQUIRE(r);
  CHECK(r->options.mqtt_enabled);
  CHECK_FALSE(r->options.mqtt_tls);
  CHECK(r->options.mqtt_port == 1883);
  r = parse({"--mqtt", "mqtt://broker.plant:11883"});
  REQUIRE(r);
  CHECK(r->options.mqtt_port == 11883);
}

TEST_CASE("mqtts:// is TLS on port 8883 and takes the CA, the client certificate and its key") {
  Files f;
  const auto r = parse({"--mqtt", "mqtts://broker.plant", "--mqtt-ca", f.ca, "--mqtt-cert", f.cert, "--mqtt-key", f.key});
  REQUIRE(r);
  CHECK(r->options.mqtt_tls);
  CHECK(r->options.mqtt_port == 8883);
  CHECK(r->options.mqtt_ca == f.ca);
  CHECK(r->options.mqtt_cert == f.cert);
  CHECK(r->options.mqtt_key == f.key);
}

TEST_CASE("mqtts:// without --mqtt-ca is refused: the broker could not be checked") {
  const auto r = parse({"--mqtt", "mqtts://broker.plant"});
  REQUIRE_FALSE(r);
  CHECK(r.error().find("needs --mqtt-ca") != std::string::npos);
}

TEST_CASE("TLS files with plain mqtt:// are refused naming the file option") {
  Files f;
  const auto r = parse({"--mqtt", "mqtt://broker.plant", "--mqtt-ca", f.ca});
  REQUIRE_FALSE(r);
  CHECK(r.error().find("--mqtt-ca is set") != std::string::npos);
  CHECK(r.error().find("mqtts://") != std::string::npos);
}

TEST_CASE("a client certificate without its key, or a key without its certificate, is refused") {
  Files f;
  auto r = parse({"--mqtt", "mqtts://b", "--mqtt-ca", f.ca, "--mqtt-cert", f.cert});
  REQUIRE_FALSE(r);
  CHECK(r.error().find("--mqtt-cert and --mqtt-key go together") != std::string::npos);
  r = parse({"--mqtt", "mqtts://b", "--mqtt-ca", f.ca, "--mqtt-key", f.key});
  REQUIRE_FALSE(r);
  CHECK(r.error().find("--mqtt-cert and --mqtt-key go together") != std::string::npos);
}

TEST_CASE("a TLS file that does not exist is refused naming the option and the path") {
  const auto r = parse({"--mqtt", "mqtts://b", "--mqtt-ca", "/nonexistent/ca.crt"});
  REQUIRE_FALSE(r);
  CHECK(r.error().find("--mqtt-ca") != std::string::npos);
  CHECK(r.error().find("/nonexistent/ca.crt") != std::string::npos);
}

TEST_CASE("a password file needs a user name") {
  Files f;
  const auto r = parse({"--mqtt", "mqtt://b", "--mqtt-password-file", f.pw});
  REQUIRE_FALSE(r);
  CHECK(r.error().find("--mqtt-password-file needs --mqtt-user") != std::string::npos);
}

TEST_CASE("MQTT options without --mqtt are refused") {
  Files f;
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"--mqtt-user", "m"}, {"--mqtt-ca", f.ca}, {"--mqtt-password-file", f.pw}}) {
    const auto r = parse(args);
    REQUIRE_FALSE(r);
    CHECK(r.error().find("is set but --mqtt is not") != std::string::npos);
  }
}

TEST_CASE("the password is the first line of its file, without the line end") {
  Files f;
  const auto r = parse({"--mqtt", "mqtt://b", "--mqtt-user", "module", "--mqtt-password-file", f.pw});
  REQUIRE(r);
  const auto c = server::mqtt_config(r->options);
  REQUIRE(c);
  CHECK(c->user == "module");
  CHECK(c->password == "s3cret");
}

TEST_CASE("an empty password file is refused naming the file") {
  Files f;
  test_support::write_text(f.pw, "");
  const auto r = parse({"--mqtt", "mqtt://b", "--mqtt-user", "module", "--mqtt-password-file", f.pw});
  REQUIRE(r);
  const auto c = server::mqtt_config(r->options);
  REQUIRE_FALSE(c);
  CHECK(c.error().find(f.pw) != std::string::npos);
  CHECK(c.error().find("empty") != std::string::npos);
}
