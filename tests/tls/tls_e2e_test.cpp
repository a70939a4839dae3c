// Modbus/TCP Security against the real homingd on loopback, with a client made
// here on OpenSSL (tests/support/tls_modbus_client.hpp, no libmodbus) and the
// certificates of the README's recipe: roles decide what a client may write,
// and every certificate the module must not trust is refused at the handshake
// with a log line naming the client's address, the certificate and the reason.
#include <arpa/inet.h>
#include <catch2/catch.hpp>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>

#include "daemon.hpp"
#include "homing/status.hpp"
#include "persistence/settings_store.hpp"
#include "registers/defaults.hpp"
#include "registers/errors.hpp"
#include "tests/support/test_pki.hpp"
#include "tests/support/tls_modbus_client.hpp"
#include "tls/context.hpp"

using namespace e2e;

namespace {

// A homingd serving Modbus/TCP Security (with the CRL unless told otherwise)
// beside plain TCP.
DaemonOptions tls_options(std::vector<std::string> extra = {}, bool with_crl = true) {
  DaemonOptions o;
  o.tls = tls_server_options(with_crl);
  o.extra = std::move(extra);
  return o;
}

TlsModbusClient connect_as_identity(const Daemon& d, const TlsIdentity& id) {
  auto c = TlsModbusClient::connect(d.tls_port(), id);
  if (!c) FAIL("cannot connect with " << id.cert << ": " << c.error());
  return std::move(*c);
}

TlsModbusClient connect_as(const Daemon& d, std::string_view name) { return connect_as_identity(d, tls_identity(name)); }

const std::vector<std::uint8_t> kReadState{4, 0x00, 0x01, 0x00, 0x01};  // FC4 status.state

// Why the module refused this identity: the handshake's error or, in TLS 1.3
// (where the client's side of the handshake ends before the module has
// checked its certificate), the first request's. Empty when not refused.
std::string refusal(const Daemon& d, const TlsIdentity& id) {
  auto c = TlsModbusClient::connect(d.tls_port(), id);
  if (!c) return c.error();
  auto r = c->transaction(1, kReadState);
  return r ? std::string() : r.error();
}

// The daemon's log gets a line containing every one of `parts` (bounded wait).
bool log_has(const Daemon& d, std::initializer_list<std::string_view> parts) {
  const auto line_has_all = [&] {
    const std::string log = d.log();
    std::size_t start = 0;
    while (start < log.size()) {
      const std::size_t end = std::min(log.find('\n', start), log.size());
      const std::string_view line(log.data() + start, end - start);
      if (std::all_of(parts.begin(), parts.end(), [&](std::string_view p) { return line.find(p) != line.npos; }))
        return true;
      start = end + 1;
    }
    return false;
  };
  return wait_until(line_has_all, 5s);
}

bool homing_started(TlsModbusClient& c) {
  return wait_until(
      [&] {
        return c.read("status.homing") == 1 ||
               c.read("status.state") == static_cast<int>(homing::MachineState::homed);
      },
      5s);
}

std::vector<persistence::AuditEntry> audit_of(const std::string& db) {
  std::vector<persistence::SettingDefault> defaults;
  for (const auto& [name, value] : registers::persisted_defaults()) defaults.push_back({name, value});
  persistence::OpenReport report;
  auto store = persistence::SettingsStore::open(db, defaults, report);
  REQUIRE(store);
  auto changes = store->recent_changes(10);
  REQUIRE(changes);
  return *changes;
}

}  // namespace

TEST_CASE("an engineer certificate reads and writes settings over TLS and the audit log names its subject") {
  Daemon d(tls_options());
  CHECK(d.listening_line().find("tls 127.0.0.1:" + std::to_string(d.tls_port())) != std::string::npos);
  auto c = connect_as(d, "engineer");
  CHECK(c.read("status.state") == static_cast<int>(homing::MachineState::not_homed));
  CHECK(c.read("axis.x.seek_feedrate") == 1000);
  REQUIRE(c.write("axis.x.seek_feedrate", 1200) == 0);
  CHECK(c.read("axis.x.seek_feedrate") == 1200);
  REQUIRE(c.write("sim.x.sensor_max", um(1.5)) == 0);  // the simulator unit too
  CHECK(c.read("sim.x.sensor_max") == um(1.5));
  CHECK(log_has(d, {"tls: client 127.0.0.1:", "CN=engineer", "(role engineer)", "connected"}));

  REQUIRE(d.stop() == 0);
  const auto audit = audit_of(d.db());
  REQUIRE_FALSE(audit.empty());
  CHECK(audit.front().name == "axis.x.seek_feedrate");
  CHECK(audit.front().transport == "tls");
  CHECK(audit.front().client.find("127.0.0.1:") == 0);
  CHECK(audit.front().client.find("CN=engineer,O=Homing module (role engineer)") != std::string::npos);
}

TEST_CASE("an operator certificate homes the machine but a settings write gets exception 01 and changes nothing") {
  Daemon d(tls_options());
  auto c = connect_as(d, "operator");
  CHECK(c.write("host.heartbeat", 7) == 0);
  CHECK(c.read("host.heartbeat") == 7);
  CHECK(c.write("axis.x.target", um(5)) == 0);
  CHECK(c.write("axis.x.seek_feedrate", 1200) == 1);
  CHECK(c.read("axis.x.seek_feedrate") == 1000);
  CHECK(c.write("security.unlock", 1234) == 1);
  CHECK(c.write("cmd.lock_settings", 1) == 1);
  CHECK(c.write("sim.x.sensor_max", um(1.5)) == 1);
  CHECK(c.read("sim.x.sensor_max") == 0);
  CHECK(log_has(d, {"tls 127.0.0.1:", "write refused with exception 01", "reason 16 (role)", "CN=operator",
                    "may not write settings"}));
  // Counted and published like every other refused write: the last one was the simulator write.
  CHECK(c.read("status.refusal_count") == 4);
  CHECK(c.read("status.last_refusal_reason") == static_cast<int>(registers::RefusalReason::role));
  CHECK(c.read("status.last_refused_register") == reg("sim.x.sensor_max").address);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  CHECK(homing_started(c));
}

TEST_CASE("a viewer certificate reads everything but every write gets exception 01") {
  Daemon d(tls_options());
  auto c = connect_as(d, "viewer");
  CHECK(c.read("axis.x.seek_feedrate") == 1000);
  CHECK(c.read("status.homing") == 0);
  CHECK(c.read("sim.x.sensor_max") == 0);
  CHECK(c.write("cmd.home_all", 1) == 1);
  CHECK(c.write("host.heartbeat", 7) == 1);
  CHECK(c.write("host.homing_permit", 1) == 1);
  CHECK(c.write("axis.x.seek_feedrate", 1200) == 1);
  CHECK(c.read("host.heartbeat") == 0);
  CHECK(c.read("axis.x.seek_feedrate") == 1000);
  std::this_thread::sleep_for(300ms);
  CHECK(c.read("status.homing") == 0);
  CHECK(log_has(d, {"tls 127.0.0.1:", "write refused with exception 01", "reason 16 (role)", "CN=viewer",
                    "may only read"}));
  CHECK(c.read("status.refusal_count") == 4);
}

TEST_CASE("a certificate without a role gets --tls-default-role, viewer unless set") {
  SECTION("viewer by default") {
    Daemon d(tls_options());
    auto c = connect_as(d, "no-role");
    CHECK(c.read("status.homing") == 0);
    CHECK(c.write("cmd.home_all", 1) == 1);
    CHECK(log_has(d, {"CN=no-role", "(role viewer, by --tls-default-role)", "connected"}));
  }
  SECTION("operator when set") {
    Daemon d(tls_options({"--tls-default-role", "operator"}));
    auto c = connect_as(d, "no-role");
    CHECK(c.write("axis.x.seek_feedrate", 1200) == 1);
    REQUIRE(c.write("cmd.home_all", 1) == 0);
    CHECK(homing_started(c));
  }
  SECTION("refused when set to none") {
    Daemon d(tls_options({"--tls-default-role", "none"}));
    CHECK_FALSE(refusal(d, tls_identity("no-role")).empty());
    CHECK(log_has(d, {"tls: refused 127.0.0.1:", "CN=no-role", "has no role", "it gets nothing"}));
  }
}

TEST_CASE("a certificate with an unknown role gets nothing, not even a read, and the log says why") {
  Daemon d(tls_options());
  CHECK_FALSE(refusal(d, tls_identity("unknown-role")).empty());
  CHECK(log_has(d, {"tls: refused 127.0.0.1:", "CN=unknown-role", "has role 'admin'",
                    "not viewer, operator or engineer"}));
}

TEST_CASE("TLS 1.2 and 1.3 are spoken, TLS 1.1 is refused") {
  Daemon d(tls_options());
  const auto context = [](std::string_view name, int min_version, int max_version) {
    const TlsIdentity id = tls_identity(name);
    auto ctx = tls::client_context({id.cert, id.key, id.ca});
    REQUIRE(ctx);
    // TLS 1.1 signs with SHA-1, which OpenSSL 3 refuses above security level 0.
    if (max_version < TLS1_2_VERSION) REQUIRE(SSL_CTX_set_cipher_list(ctx->get(), "DEFAULT:@SECLEVEL=0") == 1);
    SSL_CTX_set_min_proto_version(ctx->get(), min_version);
    SSL_CTX_set_max_proto_version(ctx->get(), max_version);
    return std::move(*ctx);
  };
  auto v13 = TlsModbusClient::connect(d.tls_port(), context("viewer", TLS1_3_VERSION, TLS1_3_VERSION));
  REQUIRE(v13);
  CHECK(v13->protocol_version() == TLS1_3_VERSION);
  CHECK(v13->read("status.homing") == 0);
  auto v12 = TlsModbusClient::connect(d.tls_port(), context("viewer", TLS1_2_VERSION, TLS1_2_VERSION));
  REQUIRE(v12);
  CHECK(v12->protocol_version() == TLS1_2_VERSION);
  CHECK(v12->read("status.homing") == 0);
  // In TLS 1.2 the module checks the client's certificate before the client's handshake ends.
  auto expired = TlsModbusClient::connect(d.tls_port(), context("expired", TLS1_2_VERSION, TLS1_2_VERSION));
  REQUIRE_FALSE(expired);
  CHECK(expired.error().find("certificate expired") != std::string::npos);
  auto v11 = TlsModbusClient::connect(d.tls_port(), context("viewer", TLS1_1_VERSION, TLS1_1_VERSION));
  REQUIRE_FALSE(v11);
  INFO(v11.error());
  CHECK(log_has(d, {"tls: refused 127.0.0.1:", "TLS handshake failed", "unsupported protocol"}));
}

TEST_CASE("a client without a certificate is refused at the handshake") {
  Daemon d(tls_options());
  const std::string why = refusal(d, tls_identity(""));
  INFO(why);
  CHECK(why.find("certificate required") != std::string::npos);
  CHECK(log_has(d, {"tls: refused 127.0.0.1:", "the client sent no certificate"}));
}

TEST_CASE("a certificate signed by another CA is refused at the handshake and the log names it") {
  Daemon d(tls_options());
  const std::string why = refusal(d, tls_identity("other-ca-engineer"));
  INFO(why);
  CHECK(why.find("unknown ca") != std::string::npos);
  CHECK(log_has(d, {"tls: refused 127.0.0.1:", "certificate CN=other-ca-engineer,O=Elsewhere refused",
                    "not signed by the CA of --tls-ca"}));
}

TEST_CASE("an expired certificate is refused at the handshake and the log says since when") {
  Daemon d(tls_options());
  const std::string why = refusal(d, tls_identity("expired"));
  INFO(why);
  CHECK(why.find("certificate expired") != std::string::npos);
  CHECK(log_has(d, {"tls: refused 127.0.0.1:", "CN=expired", "certificate has expired",
                    "valid until 2021-01-01 00:00:00 UTC"}));
}

TEST_CASE("a client refused at the handshake again and again is one log line and then a count per interval") {
  Daemon d(tls_options({"--refusal-log-interval-s", "1"}));
  constexpr int kTries = 20;
  for (int i = 0; i < kTries; ++i) CHECK_FALSE(refusal(d, tls_identity("expired")).empty());
  // A client that connects and closes without a handshake (a health check on the port).
  for (int i = 0; i < kTries; ++i) {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<std::uint16_t>(d.tls_port()));
    CHECK(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0);
    ::close(fd);
  }
  REQUIRE(log_has(d, {"tls 127.0.0.1:", "more connections refused", "certificate has expired"}));
  const std::string log = d.log();
  const auto lines_with = [&](std::string_view a, std::string_view b) {
    int n = 0;
    std::size_t start = 0;
    while (start < log.size()) {
      const std::size_t end = std::min(log.find('\n', start), log.size());
      const std::string_view line(log.data() + start, end - start);
      if (line.find(a) != line.npos && line.find(b) != line.npos) ++n;
      start = end + 1;
    }
    return n;
  };
  INFO(log);
  CHECK(lines_with("tls: refused 127.0.0.1:", "certificate has expired") == 1);
  CHECK(lines_with("tls: refused 127.0.0.1:", "closed before the TLS handshake") <= 2);
  // Still refused, still served to the others.
  CHECK(refusal(d, tls_identity("engineer")).empty());
}

TEST_CASE("a certificate that is not valid yet is refused at the handshake") {
  Daemon d(tls_options());
  CHECK_FALSE(refusal(d, tls_identity("not-yet-valid")).empty());
  CHECK(log_has(d, {"tls: refused 127.0.0.1:", "CN=not-yet-valid", "certificate is not yet valid",
                    "valid from 2040-01-01 00:00:00 UTC"}));
}

TEST_CASE("a revoked certificate is refused when homingd has the CRL, and accepted without it") {
  {
    Daemon d(tls_options());
    const std::string why = refusal(d, tls_identity("revoked"));
    INFO(why);
    CHECK(why.find("certificate revoked") != std::string::npos);
    CHECK(log_has(d, {"tls: refused 127.0.0.1:", "CN=revoked", "certificate revoked", "revoked by --tls-crl"}));
    CHECK(refusal(d, tls_identity("engineer")).empty());
  }
  Daemon without_crl(tls_options({}, false));
  CHECK(refusal(without_crl, tls_identity("revoked")).empty());
}

TEST_CASE("plain Modbus TCP on the TLS port is refused and the log says what it looked like") {
  Daemon d(tls_options());
  CHECK(raw_tcp_transaction(d.tls_port(), 1, kReadState, 1000ms).empty());
  CHECK(log_has(d, {"tls: refused 127.0.0.1:", "not a TLS handshake (first byte 0x12)", "plain Modbus TCP"}));
  // raw_tcp_transaction sends transaction id 0x1234. The plain TCP port is unaffected.
  CHECK(raw_tcp_transaction(d.port(), 1, kReadState).size() == 4);
}

TEST_CASE("SIGHUP reloads the TLS files: a certificate revoked meanwhile is refused, a broken file changes nothing") {
  TempDir dir;
  const std::string pki = dir.file("pki");
  make_certs({"init", pki});
  const auto file = [&](const std::string& name) { return pki + "/" + name; };
  const auto identity = [&](const std::string& name) {
    return TlsIdentity{file(name + ".crt"), file(name + ".key"), file("ca.crt")};
  };
  DaemonOptions o;
  o.tls = {"--tls-cert", file("server.crt"), "--tls-key", file("server.key"), "--tls-ca", file("ca.crt"),
           "--tls-crl", file("crl.pem")};
  Daemon d(o);
  auto held = connect_as_identity(d, identity("operator"));  // open before the reload: keeps working
  REQUIRE(refusal(d, identity("operator")).empty());

  make_certs({"revoke", pki, "operator"});
  REQUIRE(refusal(d, identity("operator")).empty());  // the CRL is read at start ...
  REQUIRE(::kill(d.pid(), SIGHUP) == 0);             // ... and again on SIGHUP
  REQUIRE(log_has(d, {"SIGHUP received: TLS files reloaded", file("crl.pem")}));
  CHECK_THAT(refusal(d, identity("operator")), Catch::Contains("certificate revoked"));
  CHECK(refusal(d, identity("engineer")).empty());
  CHECK(held.read("status.state") >= 0);

  // A file that cannot be read: logged, and the files read before stay in use.
  test_support::write_text(file("crl.pem"), "not a CRL\n");
  REQUIRE(::kill(d.pid(), SIGHUP) == 0);
  CHECK(log_has(d, {"SIGHUP received: TLS files not reloaded, the previous ones stay in use", "crl.pem"}));
  CHECK_THAT(refusal(d, identity("operator")), Catch::Contains("certificate revoked"));
  CHECK(refusal(d, identity("engineer")).empty());
  CHECK(d.stop() == 0);
}

TEST_CASE("a stalled TLS handshake does not delay a polling client and is dropped within the handshake timeout") {
  Daemon d(tls_options());
  // A ClientHello record header announcing 512 bytes, and then nothing.
  const int stalled = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<std::uint16_t>(d.tls_port()));
  REQUIRE(::connect(stalled, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0);
  const std::uint8_t partial[] = {0x16, 0x03, 0x01, 0x02, 0x00, 0x01};
  REQUIRE(::send(stalled, partial, sizeof partial, MSG_NOSIGNAL) == sizeof partial);
  const auto stalled_at = Clock::now();

  auto c = connect_as(d, "viewer");
  double worst_ms = 0;
  for (int i = 0; i < 50; ++i) {
    const auto t0 = Clock::now();
    REQUIRE(c.read("status.state") >= 0);
    worst_ms = std::max(worst_ms, std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  INFO("slowest poll " << worst_ms << " ms");
  CHECK(worst_ms < 1500);  // the stall lasts 3000 ms: had it held the polling client, this would show it
  CHECK(log_has(d, {"tls: refused 127.0.0.1:", "TLS handshake not finished within 3000 ms"}));
  const double dropped_after_s = std::chrono::duration<double>(Clock::now() - stalled_at).count();
  CHECK(dropped_after_s < 8.0);
  std::uint8_t byte = 0;
  CHECK(::recv(stalled, &byte, 1, 0) <= 0);  // closed by the module
  ::close(stalled);
}

TEST_CASE("the write allow-list and the unlock code still apply to an engineer over TLS") {
  SECTION("outside --write-allow") {
    Daemon d(tls_options({"--write-allow", "10.0.0.0/8"}));
    auto c = connect_as(d, "engineer");
    CHECK(c.write("axis.x.seek_feedrate", 1200) == 1);
    CHECK(c.read("axis.x.seek_feedrate") == 1000);
  }
  SECTION("settings locked by --unlock-code") {
    Daemon d(tls_options({"--unlock-code", "4711"}));
    auto c = connect_as(d, "engineer");
    CHECK(c.write("axis.x.seek_feedrate", 1200) == 4);
    REQUIRE(c.write("security.unlock", 4711) == 0);
    CHECK(c.write("axis.x.seek_feedrate", 1200) == 0);
    // Who unlocked is the certificate, as in every other TLS line.
    CHECK(log_has(d, {"settings unlocked by tls 127.0.0.1:", "CN=engineer", "(role engineer)"}));
  }
}

TEST_CASE("requests a TLS client sends back to back are all answered in order, in one record or one record each") {
  // Many more than a connection's share of a turn (16 frames), and in one
  // record more bytes than a connection takes in at once (2048): the rest are
  // served in later turns, also those the TLS session has already decrypted,
  // which the socket no longer shows to the loop.
  Daemon d(tls_options());
  auto c = connect_as(d, "engineer");
  for (const bool one_record : {true, false}) {
    INFO((one_record ? "one record" : "one record each"));
    std::vector<std::vector<std::uint8_t>> pdus(200, kReadState);
    const auto replies = c.pipeline(1, pdus, one_record);
    REQUIRE(replies);
    REQUIRE(replies->size() == pdus.size());
    for (std::size_t i = 1; i < replies->size(); ++i)
      CHECK((*replies)[i].first == static_cast<std::uint16_t>((*replies)[i - 1].first + 1));
    for (const auto& [tid, pdu] : *replies) CHECK(pdu.size() == 4);  // FC4, 2 bytes, one register
  }
}

TEST_CASE("homingd serves only TLS with --no-tcp --tls") {
  DaemonOptions o = tls_options();
  o.tcp = false;
  Daemon d(o);
  CHECK(d.listening_line().find("tcp ") == std::string::npos);
  auto c = connect_as(d, "viewer");
  CHECK(c.read("status.homing") == 0);
}

TEST_CASE("homingd does not start when a TLS file cannot be used and names it") {
  TempDir dir;
  const std::string pki = test_pki() + "/";
  auto start = [&](std::vector<std::string> tls) {
    std::vector<std::string> argv{homingd_path(), "--db", dir.file("s.db"), "--tcp", "127.0.0.1:" + std::to_string(free_port()),
                                  "--tls", "127.0.0.1:" + std::to_string(free_port())};
    argv.insert(argv.end(), tls.begin(), tls.end());
    return run_program(argv, 30s);
  };
  auto r = start({"--tls-cert", pki + "missing.crt", "--tls-key", pki + "server.key", "--tls-ca", pki + "ca.crt"});
  INFO(r.err);
  CHECK(r.code() == 1);
  CHECK(r.err.find("--tls: certificate " + pki + "missing.crt") != std::string::npos);

  // A file the system cannot open: its reason, not OpenSSL's "error 2; system lib" (and no pass-phrase hint).
  r = start({"--tls-cert", pki + "server.crt", "--tls-key", pki + "missing.key", "--tls-ca", pki + "ca.crt"});
  INFO(r.err);
  CHECK(r.code() == 1);
  CHECK(r.err.find("--tls: private key " + pki + "missing.key: cannot be read: No such file or directory") !=
        std::string::npos);
  CHECK(r.err.find("pass phrase") == std::string::npos);
  r = start({"--tls-cert", pki + "server.crt", "--tls-key", pki + "server.key", "--tls-ca", pki + "missing-ca.crt"});
  INFO(r.err);
  CHECK(r.code() == 1);
  CHECK(r.err.find("--tls: CA certificate " + pki + "missing-ca.crt: cannot be read: No such file or directory") !=
        std::string::npos);

  r = start({"--tls-cert", pki + "server.crt", "--tls-key", pki + "viewer.key", "--tls-ca", pki + "ca.crt"});
  INFO(r.err);
  CHECK(r.code() == 1);
  CHECK(r.err.find("does not belong to certificate " + pki + "server.crt") != std::string::npos);

  r = start({"--tls-cert", pki + "server.crt", "--tls-key", pki + "server.key", "--tls-ca", pki + "ca.crt",
             "--tls-crl", pki + "ca.crt"});
  INFO(r.err);
  CHECK(r.code() == 1);
  CHECK(r.err.find("--tls: CRL " + pki + "ca.crt: no PEM CRL in it") != std::string::npos);

  r = start({"--tls-cert", pki + "server.crt"});
  INFO(r.err);
  CHECK(r.code() == 2);
  CHECK(r.err.find("--tls needs --tls-cert, --tls-key and --tls-ca") != std::string::npos);
}
