#include "tls_channel.hpp"

#include <fcntl.h>
#include <openssl/x509_vfy.h>
#include <fmt/format.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>

#include "channel_stream.hpp"
#include "client_role.hpp"
#include "tls/certificate.hpp"
#include "tls/session.hpp"

namespace server {
namespace {

using Status = ChannelIo::Status;

ChannelIo::Status status_of(tls::Progress p) {
  switch (p) {
    case tls::Progress::done: return Status::done;
    case tls::Progress::want_read: return Status::want_read;
    case tls::Progress::want_write: return Status::want_write;
    case tls::Progress::closed:
    case tls::Progress::failed: return Status::closed;
  }
  return Status::closed;
}

// A TLS session on the connection's socket (not owned); says goodbye
// (close_notify) when it goes.
class TlsChannel final : public ByteChannel {
 public:
  TlsChannel(int fd, tls::Session session) : fd_(fd), session_(std::move(session)) {}
  ~TlsChannel() override { session_.close(); }
  int fd() const override { return fd_; }
  ChannelIo read(std::span<std::uint8_t> out) override {
    const tls::Io io = session_.read(out);
    return {status_of(io.progress), io.bytes};
  }
  ChannelIo write(std::span<const std::uint8_t> bytes) override {
    const tls::Io io = session_.write(bytes);
    return {status_of(io.progress), io.bytes};
  }
  bool buffered() const override { return session_.pending(); }

 private:
  int fd_;
  tls::Session session_;
};

// What a technician checks for each way a certificate is refused.
std::string_view hint(int code) {
  switch (code) {
    case X509_V_ERR_UNABLE_TO_GET_ISSUER_CERT_LOCALLY:
    case X509_V_ERR_UNABLE_TO_GET_ISSUER_CERT:
    case X509_V_ERR_UNABLE_TO_VERIFY_LEAF_SIGNATURE:
    case X509_V_ERR_DEPTH_ZERO_SELF_SIGNED_CERT:
    case X509_V_ERR_SELF_SIGNED_CERT_IN_CHAIN:
    case X509_V_ERR_CERT_SIGNATURE_FAILURE: return "it is not signed by the CA of --tls-ca";
    case X509_V_ERR_CERT_REVOKED: return "it is revoked by --tls-crl";
    case X509_V_ERR_CERT_HAS_EXPIRED: return "make the client a new certificate";
    case X509_V_ERR_CERT_NOT_YET_VALID: return "is the module's clock right?";
    case X509_V_ERR_UNABLE_TO_GET_CRL: return "--tls-crl has no CRL of the CA that signed it";
    case X509_V_ERR_CRL_HAS_EXPIRED: return "the CRL of --tls-crl is past its next update: issue a fresh one";
    case X509_V_ERR_CRL_NOT_YET_VALID: return "the CRL of --tls-crl is not valid yet: is the module's clock right?";
    case X509_V_ERR_INVALID_PURPOSE: return "it is not made for TLS clients (extendedKeyUsage clientAuth)";
    default: return "";
  }
}

std::string handshake_failure(const tls::Session& session) {
  if (auto refused = tls::verify_failure(session.ssl())) {
    std::string text = "certificate " + refused->subject + " refused: " + refused->reason;
    if (!refused->detail.empty()) text += " (" + refused->detail + ")";
    if (const auto h = hint(refused->code); !h.empty()) text += "; " + std::string(h);
    return text;
  }
  if (session.error().find("peer did not return a certificate") != std::string::npos)
    return "the client sent no certificate; one signed by the CA of --tls-ca is required";
  return "TLS handshake failed: " + session.error();
}

// The first byte of a TLS connection is a handshake record (0x16); anything
// else is most likely a plain Modbus TCP client on the TLS port.
std::expected<void, std::string> expect_tls(int fd, Deadline deadline, const std::atomic<bool>& stop) {
  if (!wait_ready(fd, Status::want_read, deadline, stop))
    return std::unexpected(fmt::format("no TLS handshake within {} ms of connecting", kHandshakeTimeoutMs));
  std::uint8_t first = 0;
  const ssize_t r = ::recv(fd, &first, 1, MSG_PEEK);
  if (r <= 0) return std::unexpected("closed before the TLS handshake");
  if (first != 0x16)
    return std::unexpected(fmt::format("not a TLS handshake (first byte 0x{:02X}): plain Modbus TCP on the TLS port? "
                                       "Modbus/TCP Security clients begin with a TLS ClientHello",
                                       first));
  return {};
}

// A refused client must be able to read the alert that says why: closing the
// socket with its last handshake messages unread would reset the connection,
// and a reset can discard the alert before the client reads it. So the
// module's side is closed first and the rest of what the client sends is
// read and dropped, briefly.
void let_the_alert_arrive(int fd, const std::atomic<bool>& stop) {
  ::shutdown(fd, SHUT_WR);
  const Deadline until = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
  std::uint8_t sink[512];
  while (wait_ready(fd, Status::want_read, until, stop)) {
    const ssize_t r = ::recv(fd, sink, sizeof sink, MSG_DONTWAIT);
    if (r == 0 || (r < 0 && errno != EAGAIN && errno != EINTR)) break;
  }
}

}  // namespace

std::expected<std::unique_ptr<TlsOpener>, std::string> TlsOpener::create(const TlsConfig& config) {
  if (config.default_role != "none" && !access_of_role(config.default_role))
    return std::unexpected("--tls-default-role " + config.default_role + ": not a role (viewer, operator, engineer, none)");
  auto ctx = tls::server_context(config.files);
  if (!ctx) return std::unexpected("--tls: " + ctx.error());
  return std::unique_ptr<TlsOpener>(new TlsOpener(std::move(*ctx), config));
}

TlsOpener::TlsOpener(tls::SslCtx ctx, TlsConfig config)
    : config_(std::move(config)), ctx_(ctx.release(), SSL_CTX_free) {}

std::shared_ptr<SSL_CTX> TlsOpener::context() const {
  std::lock_guard lock(mutex_);
  return ctx_;
}

std::expected<void, std::string> TlsOpener::reload() {
  auto ctx = tls::server_context(config_.files);
  if (!ctx) return std::unexpected(ctx.error());
  std::shared_ptr<SSL_CTX> fresh(ctx->release(), SSL_CTX_free);
  std::lock_guard lock(mutex_);
  ctx_ = std::move(fresh);
  return {};
}

std::expected<std::unique_ptr<ByteChannel>, std::string> TlsOpener::open(int fd, ClientInfo& client,
                                                                          const std::atomic<bool>& stop) {
  const Deadline deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(kHandshakeTimeoutMs);
  if (::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK) != 0)
    return std::unexpected(std::string("cannot make the socket non-blocking: ") + std::strerror(errno));
  if (auto r = expect_tls(fd, deadline, stop); !r) return std::unexpected(r.error());
  // The session holds its own reference to the context (SSL_new), so a
  // reload meanwhile does not pull it away.
  auto session = tls::Session::accept(context().get(), fd);
  if (!session) return std::unexpected(session.error());
  for (;;) {
    const tls::Progress p = session->handshake();
    if (p == tls::Progress::done) break;
    if (p == tls::Progress::closed || p == tls::Progress::failed) {
      let_the_alert_arrive(fd, stop);
      return std::unexpected(handshake_failure(*session));
    }
    if (!wait_ready(fd, status_of(p), deadline, stop))
      return std::unexpected(fmt::format("TLS handshake not finished within {} ms of connecting", kHandshakeTimeoutMs));
  }
  if (auto admitted = admit(session->ssl(), client); !admitted) {
    session->close();
    let_the_alert_arrive(fd, stop);
    return std::unexpected(admitted.error());
  }
  return std::make_unique<TlsChannel>(fd, std::move(*session));
}

std::expected<void, std::string> TlsOpener::admit(SSL* ssl, ClientInfo& client) const {
  const X509* cert = SSL_get0_peer_certificate(ssl);
  if (!cert) return std::unexpected("the client sent no certificate");
  const std::string subject = tls::subject_of(cert);
  const auto role = tls::role_of(cert);
  if (!role) return std::unexpected("certificate " + subject + ": " + role.error() + "; it gets nothing");
  if (!*role && config_.default_role == "none")
    return std::unexpected("certificate " + subject + " has no role (extension " + tls::kRoleOid +
                           ") and --tls-default-role is none; it gets nothing");
  const std::string name = role->value_or(config_.default_role);
  const auto access = access_of_role(name);
  if (!access)
    return std::unexpected("certificate " + subject + " has role '" + name +
                           "', which is not viewer, operator or engineer; it gets nothing");
  client.access = *access;
  client.identity = subject + " (role " + name + (*role ? ")" : ", by --tls-default-role)");
  return {};
}

}  // namespace server
