#pragma once
// The certificates the Modbus/TCP Security tests use, made by the recipe the
// README gives (tools/tls/make-certs.sh init DIR --test-set): once per build
// tree and script version, shared by every test process.
#include <string>
#include <string_view>
#include <vector>

namespace test_support {

// The directory holding ca.crt, server.crt/.key, engineer, operator, viewer,
// no-role, unknown-role, expired, not-yet-valid, revoked, other-ca-engineer
// (.crt/.key) and crl.pem. Throws with the script's output when it fails.
const std::string& test_pki();

// Runs tools/tls/make-certs.sh with `args` (a PKI of a test's own: init,
// revoke, crl...); throws with the script's output when it fails.
void make_certs(std::vector<std::string> args);

// What a client shows: its certificate and key (empty: none) and the CA it
// checks the module's certificate against.
struct TlsIdentity {
  std::string cert, key, ca;
};
// The test PKI's certificate `name` ("" for a client without one).
TlsIdentity tls_identity(std::string_view name);

// homingd's options for Modbus/TCP Security with the test PKI's server
// certificate, after --tls HOST:PORT: --tls-cert, --tls-key, --tls-ca, and
// --tls-crl when `with_crl`.
std::vector<std::string> tls_server_options(bool with_crl = true);

}  // namespace test_support
