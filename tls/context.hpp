#pragma once
// The TLS contexts of Modbus/TCP Security: TLS 1.2 and 1.3 only, ECDHE with
// AEAD cipher suites, no renegotiation and no session resumption (every
// connection shows its certificate again, so a revoked one is refused the next
// time it connects), both sides authenticated by certificates.
#include <openssl/ssl.h>

#include <expected>
#include <optional>
#include <string>
#include <vector>

#include "tls/handles.hpp"

namespace tls {

struct ServerFiles {
  std::string cert;  // the module's certificate, PEM (its chain may follow it)
  std::string key;   // its private key, PEM, not encrypted
  std::string ca;    // the CA certificate(s) that sign client certificates, PEM
  std::string crl;   // revoked client certificates, PEM CRL(s); empty: none
};

// A context that requires a client certificate signed by files.ca (and not
// revoked by files.crl). The error names the file and what is wrong with it.
std::expected<SslCtx, std::string> server_context(const ServerFiles& files);

// What the server's files allow but a technician should fix, in words that
// say how: a private key that every user of the machine may read, a CRL past
// its next update (OpenSSL then refuses every client certificate with "CRL
// has expired") or not valid yet. Empty when nothing is; unreadable files are
// server_context's errors, not warnings.
std::vector<std::string> server_file_warnings(const ServerFiles& files);

struct ClientFiles {
  std::string cert;  // the client's certificate, PEM; empty: none is shown
  std::string key;   // its private key, PEM
  std::string ca;    // the CA that signed the server's certificate, PEM
};

// A context that verifies the server against files.ca and shows files.cert.
std::expected<SslCtx, std::string> client_context(const ClientFiles& files);

// Why the peer's certificate was refused during the handshake of `ssl`, as
// the verification saw it first; nullopt when verification refused nothing.
struct VerifyFailure {
  int code = 0;         // X509_V_ERR_*
  std::string reason;   // OpenSSL's text, e.g. "certificate has expired"
  std::string subject;  // the peer's own certificate
  std::string detail;   // when it was or will be valid, for the date errors
};
std::optional<VerifyFailure> verify_failure(const SSL* ssl);

}  // namespace tls
