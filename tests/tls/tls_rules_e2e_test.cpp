// docs/operating.md "Modbus/TCP Security (TLS)", Details: "TLS 1.2 (ECDHE with AES-GCM or
// ChaCha20-Poly1305) and TLS 1.3 only; no renegotiation; no session
// resumption", and "a CRL past its next update refuses every client until a
// fresh one is installed". The real homingd against OpenSSL clients that
// offer what the module must refuse: other TLS 1.2 suites, a renegotiation, a
// session to resume; and against every client when its CRL has expired.
#include <arpa/inet.h>
#include <catch2/catch.hpp>
#include <netinet/in.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/time.h>

#include <algorithm>
#include <memory>

#include "daemon.hpp"
#include "tests/support/test_pki.hpp"
#include "tests/support/tls_modbus_client.hpp"
#include "tls/context.hpp"

using namespace e2e;

namespace {

DaemonOptions tls_options() {
  DaemonOptions o;
  o.tls = tls_server_options();
  return o;
}

const std::vector<std::uint8_t> kReadState{4, 0x00, 0x01, 0x00, 0x01};  // FC4 status.state

// The test PKI's engineer as a TLS 1.2-only client offering `suites`.
tls::SslCtx tls12_context(const char* suites) {
  const TlsIdentity id = tls_identity("engineer");
  auto ctx = tls::client_context({id.cert, id.key, id.ca});
  REQUIRE(ctx);
  SSL_CTX_set_min_proto_version(ctx->get(), TLS1_2_VERSION);
  SSL_CTX_set_max_proto_version(ctx->get(), TLS1_2_VERSION);
  REQUIRE(SSL_CTX_set_cipher_list(ctx->get(), suites) == 1);
  return std::move(*ctx);
}

// A blocking OpenSSL connection of its own (socket timeouts bound every
// call), for what the module's own client never does: renegotiate, resume.
class RawTls {
 public:
  RawTls(int port, SSL_CTX* ctx, SSL_SESSION* resume = nullptr) : ssl_(SSL_new(ctx)) {
    REQUIRE(ssl_);
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    REQUIRE(fd_ >= 0);
    const timeval tv{5, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    REQUIRE(::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0);
    SSL_set_fd(ssl_.get(), fd_);
    SSL_set1_host(ssl_.get(), "127.0.0.1");
    if (resume) REQUIRE(SSL_set_session(ssl_.get(), resume) == 1);
    ERR_clear_error();
    const int rc = SSL_connect(ssl_.get());
    INFO(ERR_error_string(ERR_get_error(), nullptr));
    REQUIRE(rc == 1);
  }
  ~RawTls() {
    ssl_.reset();
    if (fd_ >= 0) ::close(fd_);
  }
  RawTls(const RawTls&) = delete;
  RawTls& operator=(const RawTls&) = delete;

  SSL* ssl() const { return ssl_.get(); }

  // One Modbus/TCP request and its reply; false when none came.
  bool transaction(const std::vector<std::uint8_t>& pdu) {
    std::vector<std::uint8_t> frame{0x00, 0x07, 0, 0, 0, static_cast<std::uint8_t>(pdu.size() + 1), 1};
    frame.insert(frame.end(), pdu.begin(), pdu.end());
    if (SSL_write(ssl(), frame.data(), static_cast<int>(frame.size())) != static_cast<int>(frame.size())) return false;
    std::uint8_t reply[260];
    std::size_t got = 0;
    for (int i = 0; i < 20 && (got < 7 || got < 6u + reply[5]); ++i) {
      const int n = SSL_read(ssl(), reply + got, static_cast<int>(sizeof reply - got));
      if (n <= 0) return false;
      got += static_cast<std::size_t>(n);
    }
    return got >= 9 && reply[0] == 0x00 && reply[1] == 0x07 && reply[7] == pdu[0];
  }

 private:
  struct Free {
    void operator()(SSL* s) const { SSL_free(s); }
  };
  std::unique_ptr<SSL, Free> ssl_;
  int fd_ = -1;
};

// The engineer's context for RawTls at one protocol version, with what the
// module's client turns off turned back on: renegotiation, tickets and a
// client-side session cache.
tls::SslCtx raw_context(int version) {
  const TlsIdentity id = tls_identity("engineer");
  auto ctx = tls::client_context({id.cert, id.key, id.ca});
  REQUIRE(ctx);
  SSL_CTX_set_min_proto_version(ctx->get(), version);
  SSL_CTX_set_max_proto_version(ctx->get(), version);
  SSL_CTX_clear_options(ctx->get(), SSL_OP_NO_RENEGOTIATION | SSL_OP_NO_TICKET);
  SSL_CTX_set_session_cache_mode(ctx->get(), SSL_SESS_CACHE_CLIENT);
  return std::move(*ctx);
}

bool log_has(const Daemon& d, std::string_view what) {
  return wait_until([&] { return d.log().find(what) != std::string::npos; }, 5s);
}

}  // namespace

TEST_CASE("over TLS 1.2 only ECDHE with AES-GCM or ChaCha20-Poly1305 is agreed, any other suite is refused") {
  Daemon d(tls_options());
  for (const char* suite : {"ECDHE-ECDSA-AES128-GCM-SHA256", "ECDHE-ECDSA-AES256-GCM-SHA384",
                            "ECDHE-ECDSA-CHACHA20-POLY1305"}) {
    INFO(suite);
    auto c = TlsModbusClient::connect(d.tls_port(), tls12_context(suite));
    REQUIRE(c);
    CHECK(std::string(SSL_get_cipher_name(c->ssl())) == suite);
    CHECK(c->transaction(1, kReadState));
  }
  // CBC with ECDHE, then suites without ECDHE (the module's key is EC: only
  // its ECDSA suites could ever be agreed, and these are the ones refused).
  for (const char* suite : {"ECDHE-ECDSA-AES128-SHA256", "ECDHE-ECDSA-AES256-SHA384", "ECDHE-ECDSA-AES128-SHA",
                            "ECDHE-ECDSA-AES256-SHA", "ECDHE-ECDSA-ARIA128-GCM-SHA256",
                            "ECDHE-ECDSA-CAMELLIA128-SHA256"}) {
    INFO(suite);
    auto c = TlsModbusClient::connect(d.tls_port(), tls12_context(suite));
    REQUIRE_FALSE(c);
    CHECK_THAT(c.error(), Catch::Contains("handshake failure"));
  }
  CHECK(log_has(d, "no shared cipher"));
}

TEST_CASE("a TLS 1.2 client's renegotiation is refused and the connection is not renegotiated") {
  Daemon d(tls_options());
  auto ctx = raw_context(TLS1_2_VERSION);
  RawTls c(d.tls_port(), ctx.get());
  REQUIRE(c.transaction(kReadState));
  REQUIRE(SSL_renegotiate(c.ssl()) == 1);
  ERR_clear_error();
  const int rc = SSL_do_handshake(c.ssl());
  const unsigned long why = ERR_peek_error();
  INFO(ERR_error_string(why, nullptr));
  CHECK(rc != 1);
  CHECK(ERR_GET_REASON(why) == SSL_R_NO_RENEGOTIATION);
  // The module serves others as before.
  auto other = TlsModbusClient::connect(d.tls_port(), tls_identity("viewer"));
  REQUIRE(other);
  CHECK(other->transaction(1, kReadState));
}

TEST_CASE("no TLS session is resumed: every connection makes a full handshake with its certificate") {
  for (const int version : {TLS1_2_VERSION, TLS1_3_VERSION}) {
    INFO((version == TLS1_2_VERSION ? "TLS 1.2" : "TLS 1.3"));
    Daemon d(tls_options());
    auto ctx = raw_context(version);
    SSL_SESSION* session = nullptr;
    {
      RawTls first(d.tls_port(), ctx.get());
      // In TLS 1.3 tickets come after the handshake: a transaction reads them.
      REQUIRE(first.transaction(kReadState));
      CHECK_FALSE(SSL_session_reused(first.ssl()));
      session = SSL_get1_session(first.ssl());
      REQUIRE(session);
      SSL_shutdown(first.ssl());
    }
    // Nothing to resume with: no ticket, no session id.
    CHECK_FALSE(SSL_SESSION_is_resumable(session));
    RawTls second(d.tls_port(), ctx.get(), session);
    CHECK(second.transaction(kReadState));
    CHECK_FALSE(SSL_session_reused(second.ssl()));
    SSL_SESSION_free(session);
    // Both connections showed the certificate: each is logged with its subject.
    REQUIRE(wait_until(
        [&] {
          const std::string log = d.log();
          std::size_t n = 0;
          for (std::size_t at = log.find("CN=engineer"); at != std::string::npos; at = log.find("CN=engineer", at + 1))
            ++n;
          return n >= 2;
        },
        5s));
  }
}

TEST_CASE("a CRL past its next update refuses every client until a fresh one is installed") {
  TempDir dir;
  const std::string pki = dir.file("pki");
  make_certs({"init", pki});
  const auto file = [&](const std::string& name) { return pki + "/" + name; };
  const std::string crl = file("installed-crl.pem");
  // Issued by the same CA, valid during 2020 only.
  const RunResult gen = run_program({"openssl", "ca", "-batch", "-config", file("ca-db/openssl.cnf"), "-gencrl",
                                     "-crl_lastupdate", "20200101000000Z", "-crl_nextupdate", "20210101000000Z",
                                     "-out", crl},
                                    60s);
  INFO(gen.out << gen.err);
  REQUIRE(gen.code() == 0);

  DaemonOptions o;
  o.tls = {"--tls-cert", file("server.crt"), "--tls-key", file("server.key"), "--tls-ca", file("ca.crt"),
           "--tls-crl", crl};
  Daemon d(o);
  const auto refusal = [&](const std::string& name) {
    auto c = TlsModbusClient::connect(d.tls_port(), TlsIdentity{file(name + ".crt"), file(name + ".key"),
                                                                file("ca.crt")});
    if (!c) return c.error();
    auto r = c->transaction(1, kReadState);
    return r ? std::string() : r.error();
  };
  for (const std::string name : {"engineer", "operator", "viewer"}) {
    INFO(name);
    CHECK_FALSE(refusal(name).empty());
  }
  CHECK(log_has(d, "the CRL of --tls-crl is past its next update: issue a fresh one"));
  CHECK(log_has(d, "CN=engineer"));

  // A fresh CRL from the recipe, installed and reloaded: clients are back.
  make_certs({"crl", pki});
  std::filesystem::copy_file(file("crl.pem"), crl, std::filesystem::copy_options::overwrite_existing);
  REQUIRE(::kill(d.pid(), SIGHUP) == 0);
  REQUIRE(log_has(d, "SIGHUP received: TLS files reloaded"));
  CHECK(refusal("engineer").empty());
  CHECK(refusal("viewer").empty());
}
