// homingd's Modbus/TCP Security options: --tls HOST[:PORT] (port 802 when
// not given), its files, the default role, and the config-file keys.
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

const std::vector<std::string> kFiles{"--tls-cert", "s.crt", "--tls-key", "s.key", "--tls-ca", "ca.crt"};

std::vector<std::string> with_files(std::vector<std::string> args) {
  args.insert(args.end(), kFiles.begin(), kFiles.end());
  return args;
}

}  // namespace

TEST_CASE("TLS is off unless --tls is given") {
  const auto r = parse({});
  REQUIRE(r);
  CHECK_FALSE(r->options.tls_enabled);
}

TEST_CASE("homingd --tls without a port listens on 802, the mbaps port") {
  const auto r = parse(with_files({"--tls", "0.0.0.0"}));
  REQUIRE(r);
  CHECK(r->options.tls_enabled);
  CHECK(r->options.tls_host == "0.0.0.0");
  CHECK(r->options.tls_port == 802);
  CHECK(r->options.tls_cert == "s.crt");
  CHECK(r->options.tls_key == "s.key");
  CHECK(r->options.tls_ca == "ca.crt");
  CHECK(r->options.tls_crl.empty());
  CHECK(r->options.tls_default_role == "viewer");
  CHECK(r->options.tcp_enabled);  // beside plain TCP
}

TEST_CASE("homingd --tls HOST:PORT, --tls-crl and --tls-default-role are taken as given") {
  auto args = with_files({"--tls", "127.0.0.1:8802", "--tls-crl", "crl.pem", "--tls-default-role", "none"});
  const auto r = parse(args);
  REQUIRE(r);
  CHECK(r->options.tls_port == 8802);
  CHECK(r->options.tls_crl == "crl.pem");
  CHECK(r->options.tls_default_role == "none");
}

TEST_CASE("homingd --tls is refused without its certificate, key and CA, with a bad port or an unknown default role") {
  auto r = parse({"--tls", "0.0.0.0", "--tls-cert", "s.crt"});
  REQUIRE_FALSE(r);
  CHECK(r.error().find("--tls needs --tls-cert, --tls-key and --tls-ca") != std::string::npos);
  r = parse(with_files({"--tls", "0.0.0.0:80000"}));
  REQUIRE_FALSE(r);
  CHECK(r.error().find("--tls: port 80000 is outside 1..65535") != std::string::npos);
  r = parse(with_files({"--tls", "0.0.0.0", "--tls-default-role", "admin"}));
  REQUIRE_FALSE(r);
  CHECK(r.error().find("tls-default-role") != std::string::npos);
  // A host name would have libmodbus listen on 255.255.255.255, where no client reaches.
  r = parse(with_files({"--tls", "cabinet.plant:802"}));
  REQUIRE_FALSE(r);
  CHECK(r.error().find("--tls: 'cabinet.plant' is not an IPv4 address to listen on") != std::string::npos);
}

TEST_CASE("TLS files without --tls are refused rather than silently ignored") {
  const auto r = parse({"--tls-ca", "ca.crt"});
  REQUIRE_FALSE(r);
  CHECK(r.error().find("--tls-ca is set but --tls is not") != std::string::npos);
}

TEST_CASE("homingd --no-tcp with --tls alone serves TLS only") {
  const auto r = parse(with_files({"--no-tcp", "--tls", "0.0.0.0"}));
  REQUIRE(r);
  CHECK_FALSE(r->options.tcp_enabled);
  CHECK(r->options.tls_enabled);
  const auto nothing = parse({"--no-tcp"});
  REQUIRE_FALSE(nothing);
  CHECK(nothing.error().find("--rtu DEVICE or --tls") != std::string::npos);
}

TEST_CASE("every TLS option is a config-file key too") {
  test_support::TempDir dir;
  const std::string path = dir.file("homingd.toml");
  test_support::write_text(path,
                           "tls = \"0.0.0.0\"\ntls_cert = \"/etc/homingd/tls/server.crt\"\n"
                           "tls_key = \"/etc/homingd/tls/server.key\"\ntls_ca = \"/etc/homingd/tls/ca.crt\"\n"
                           "tls_crl = \"/etc/homingd/tls/crl.pem\"\ntls_default_role = \"operator\"\n");
  const auto r = parse({"--config", path});
  REQUIRE(r);
  CHECK(r->options.tls_enabled);
  CHECK(r->options.tls_port == 802);
  CHECK(r->options.tls_cert == "/etc/homingd/tls/server.crt");
  CHECK(r->options.tls_key == "/etc/homingd/tls/server.key");
  CHECK(r->options.tls_ca == "/etc/homingd/tls/ca.crt");
  CHECK(r->options.tls_crl == "/etc/homingd/tls/crl.pem");
  CHECK(r->options.tls_default_role == "operator");
}
