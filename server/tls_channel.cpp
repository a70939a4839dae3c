#include "tls_channel.hpp"

#include <openssl/x509_vfy.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>
#include <optional>

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

// The TLS handshake of one connection as steps: the first byte checked
// (a handshake record, 0x16; anything else is most likely a plain Modbus
// TCP client on the TLS port), the handshake, then the role of the verified
// certificate.
class TlsHandshake final : public ChannelHandshake {
 public:
  TlsHandshake(int fd, std::shared_ptr<SSL_CTX> ctx, const TlsOpener& opener)
      : fd_(fd), ctx_(std::move(ctx)), opener_(opener) {}

  OpenStep step(ClientInfo& client) override {
    if (!session_) {
      std::uint8_t first = 0;
      const ssize_t r = ::recv(fd_, &first, 1, MSG_PEEK | MSG_DONTWAIT);
      if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR))
        return OpenStep::wait_for(OpenStep::Kind::want_read);
      if (r <= 0) return refused("closed before the TLS handshake");
      if (first != 0x16)
        return refused(fmt::format("not a TLS handshake (first byte 0x{:02X}): plain Modbus TCP on the TLS port? "
                                   "Modbus/TCP Security clients begin with a TLS ClientHello",
                                   first));
      // The session holds its own reference to the context (SSL_new), so a
      // reload meanwhile does not pull it away.
      auto session = tls::Session::accept(ctx_.get(), fd_);
      if (!session) return refused(session.error());
      session_.emplace(std::move(*session));
    }
    const tls::Progress p = session_->handshake();
    if (p == tls::Progress::want_read) return OpenStep::wait_for(OpenStep::Kind::want_read);
    if (p == tls::Progress::want_write) return OpenStep::wait_for(OpenStep::Kind::want_write);
    if (p != tls::Progress::done) return refused(handshake_failure(*session_), true);
    if (auto admitted = opener_.admit(session_->ssl(), client); !admitted) {
      session_->close();
      return refused(admitted.error(), true);
    }
    return OpenStep::opened();
  }

  std::unique_ptr<ByteChannel> channel() override {
    auto channel = std::make_unique<TlsChannel>(fd_, std::move(*session_));
    session_.reset();
    return channel;
  }

 private:
  static OpenStep refused(std::string reason, bool drain = false) {
    return OpenStep::refusal(std::move(reason), drain);
  }

  int fd_;
  std::shared_ptr<SSL_CTX> ctx_;
  const TlsOpener& opener_;
  std::optional<tls::Session> session_;
};

}  // namespace

std::expected<std::unique_ptr<TlsOpener>, std::string> TlsOpener::create(const TlsConfig& config) {
  if (config.default_role != "none" && !access_of_role(config.default_role))
    return std::unexpected("--tls-default-role " + config.default_role + ": not a role (viewer, operator, engineer, none)");
  auto ctx = tls::server_context(config.files);
  if (!ctx) return std::unexpected("--tls: " + ctx.error());
  for (const std::string& w : tls::server_file_warnings(config.files)) spdlog::warn("--tls: {}", w);
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
  for (const std::string& w : tls::server_file_warnings(config_.files)) spdlog::warn("--tls: {}", w);
  std::shared_ptr<SSL_CTX> fresh(ctx->release(), SSL_CTX_free);
  std::lock_guard lock(mutex_);
  ctx_ = std::move(fresh);
  return {};
}

std::unique_ptr<ChannelHandshake> TlsOpener::begin(int fd) {
  return std::make_unique<TlsHandshake>(fd, context(), *this);
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
