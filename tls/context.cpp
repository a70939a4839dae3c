#include "tls/context.hpp"

#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/x509_vfy.h>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "tls/certificate.hpp"
#include "tls/errors.hpp"

namespace tls {
namespace {

// ECDHE key exchange with AES-GCM or ChaCha20-Poly1305 for TLS 1.2; TLS 1.3's
// own suites are all AEAD and stay OpenSSL's defaults.
constexpr const char* kTls12Ciphers = "ECDHE+AESGCM:ECDHE+CHACHA20:!aNULL";

// The first refusal of a handshake's verification, owned by the SSL object
// (freed with it) so that it outlives the callback.
int report_index() {
  static const int index = SSL_get_ex_new_index(
      0, nullptr, nullptr, nullptr,
      [](void*, void* report, CRYPTO_EX_DATA*, int, long, void*) { delete static_cast<VerifyFailure*>(report); });
  return index;
}

int remember_refusal(int ok, X509_STORE_CTX* store) {
  if (ok) return ok;
  auto* ssl = static_cast<SSL*>(X509_STORE_CTX_get_ex_data(store, SSL_get_ex_data_X509_STORE_CTX_idx()));
  if (!ssl || SSL_get_ex_data(ssl, report_index())) return ok;
  auto report = std::make_unique<VerifyFailure>();
  report->code = X509_STORE_CTX_get_error(store);
  report->reason = X509_verify_cert_error_string(report->code);
  report->subject = subject_of(X509_STORE_CTX_get0_cert(store));
  const X509* at_fault = X509_STORE_CTX_get_current_cert(store);
  if (report->code == X509_V_ERR_CERT_HAS_EXPIRED && at_fault)
    report->detail = "valid until " + not_after_text(at_fault);
  if (report->code == X509_V_ERR_CERT_NOT_YET_VALID && at_fault)
    report->detail = "valid from " + not_before_text(at_fault);
  if (SSL_set_ex_data(ssl, report_index(), report.get()) == 1) report.release();
  return ok;
}

// A file OpenSSL cannot open is reported by it as "error 13; system lib";
// opened here first, the error names the system's reason (a key the service
// user may not read is the mistake commonly made).
std::expected<void, std::string> readable(const std::string& what, const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    std::string why = what + " " + path + ": cannot be read: " + std::strerror(err);
    if (err == EACCES) why += " (it must be readable by the user homingd runs as)";
    return std::unexpected(why);
  }
  ::close(fd);
  return {};
}

// What both sides share.
std::expected<SslCtx, std::string> base_context(const SSL_METHOD* method) {
  SslCtx ctx(SSL_CTX_new(method));
  if (!ctx) return std::unexpected("cannot create a TLS context: " + take_errors());
  SSL_CTX_set_min_proto_version(ctx.get(), TLS1_2_VERSION);
  if (SSL_CTX_set_cipher_list(ctx.get(), kTls12Ciphers) != 1)
    return std::unexpected("cannot set the TLS 1.2 cipher suites: " + take_errors());
  // A peer that closes without close_notify has just closed: Modbus frames
  // carry their own length, so no truncation goes unnoticed.
  SSL_CTX_set_options(ctx.get(), SSL_OP_NO_RENEGOTIATION | SSL_OP_NO_TICKET | SSL_OP_NO_COMPRESSION |
                                     SSL_OP_IGNORE_UNEXPECTED_EOF);
  SSL_CTX_set_mode(ctx.get(), SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER);
  SSL_CTX_set_session_cache_mode(ctx.get(), SSL_SESS_CACHE_OFF);
  // An encrypted key would make OpenSSL ask for its pass phrase on the terminal.
  SSL_CTX_set_default_passwd_cb(ctx.get(), [](char*, int, int, void*) { return 0; });
  return ctx;
}

std::expected<void, std::string> use_identity(SSL_CTX* ctx, const std::string& cert, const std::string& key) {
  if (auto r = readable("certificate", cert); !r) return r;
  if (auto r = readable("private key", key); !r) return r;
  if (SSL_CTX_use_certificate_chain_file(ctx, cert.c_str()) != 1)
    return std::unexpected("certificate " + cert + ": " + take_errors());
  if (SSL_CTX_use_PrivateKey_file(ctx, key.c_str(), SSL_FILETYPE_PEM) != 1) {
    const std::string why = take_errors();
    if (why.find("key values mismatch") != std::string::npos)
      return std::unexpected("private key " + key + " does not belong to certificate " + cert);
    return std::unexpected("private key " + key + ": " + why + " (a PEM key without a pass phrase is needed)");
  }
  if (SSL_CTX_check_private_key(ctx) != 1)
    return std::unexpected("private key " + key + " does not belong to certificate " + cert + ": " + take_errors());
  return {};
}

std::expected<void, std::string> trust(SSL_CTX* ctx, const std::string& ca) {
  if (auto r = readable("CA certificate", ca); !r) return r;
  if (SSL_CTX_load_verify_locations(ctx, ca.c_str(), nullptr) != 1)
    return std::unexpected("CA certificate " + ca + ": " + take_errors());
  return {};
}

std::expected<void, std::string> add_crls(SSL_CTX* ctx, const std::string& path) {
  if (auto r = readable("CRL", path); !r) return r;
  Bio in(BIO_new_file(path.c_str(), "r"));
  if (!in) return std::unexpected("CRL " + path + ": " + take_errors());
  X509_STORE* store = SSL_CTX_get_cert_store(ctx);
  int count = 0;
  while (Crl crl{PEM_read_bio_X509_CRL(in.get(), nullptr, nullptr, nullptr)}) {
    if (X509_STORE_add_crl(store, crl.get()) != 1) return std::unexpected("CRL " + path + ": " + take_errors());
    ++count;
  }
  if (count == 0) return std::unexpected("CRL " + path + ": no PEM CRL in it (" + take_errors() + ")");
  ERR_clear_error();  // the end of the file reads as "no start line"
  X509_STORE_set_flags(store, X509_V_FLAG_CRL_CHECK);
  return {};
}

}  // namespace

std::expected<SslCtx, std::string> server_context(const ServerFiles& files) {
  ERR_clear_error();
  auto ctx = base_context(TLS_server_method());
  if (!ctx) return ctx;
  SSL_CTX* c = ctx->get();
  SSL_CTX_set_options(c, SSL_OP_CIPHER_SERVER_PREFERENCE);
  SSL_CTX_set_num_tickets(c, 0);
  if (auto r = use_identity(c, files.cert, files.key); !r) return std::unexpected(r.error());
  if (auto r = trust(c, files.ca); !r) return std::unexpected(r.error());
  // The CA names sent in the certificate request let a client pick its certificate.
  STACK_OF(X509_NAME)* names = SSL_load_client_CA_file(files.ca.c_str());
  if (!names) return std::unexpected("CA certificate " + files.ca + ": " + take_errors("no certificate in it"));
  SSL_CTX_set_client_CA_list(c, names);
  if (!files.crl.empty()) {
    if (auto r = add_crls(c, files.crl); !r) return std::unexpected(r.error());
  }
  SSL_CTX_set_verify(c, SSL_VERIFY_PEER | SSL_VERIFY_FAIL_IF_NO_PEER_CERT, remember_refusal);
  return ctx;
}

std::expected<SslCtx, std::string> client_context(const ClientFiles& files) {
  ERR_clear_error();
  auto ctx = base_context(TLS_client_method());
  if (!ctx) return ctx;
  SSL_CTX* c = ctx->get();
  if (!files.cert.empty() || !files.key.empty()) {
    if (auto r = use_identity(c, files.cert, files.key.empty() ? files.cert : files.key); !r)
      return std::unexpected(r.error());
  }
  if (auto r = trust(c, files.ca); !r) return std::unexpected(r.error());
  SSL_CTX_set_verify(c, SSL_VERIFY_PEER, remember_refusal);
  return ctx;
}

std::optional<VerifyFailure> verify_failure(const SSL* ssl) {
  const auto* report = static_cast<const VerifyFailure*>(SSL_get_ex_data(ssl, report_index()));
  if (!report) return std::nullopt;
  return *report;
}

}  // namespace tls
