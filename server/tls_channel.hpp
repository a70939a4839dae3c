#pragma once
// Modbus/TCP Security on an accepted connection: the TLS handshake as steps
// the connection's event loop runs between others' requests (so it never
// delays another client), bounded by kHandshakeTimeoutMs from the accept; the client's certificate verified
// against --tls-ca (and --tls-crl); its role (server/client_role.hpp) decides
// what it may write. A refusal names the client's address, the certificate's
// subject and why.
#include <expected>
#include <memory>
#include <mutex>
#include <string>

#include "channel_opener.hpp"
#include "tls/context.hpp"

namespace server {

inline constexpr int kHandshakeTimeoutMs = 3000;

struct TlsConfig {
  tls::ServerFiles files;
  // The role of a certificate without the role extension; "none": refused.
  std::string default_role = "viewer";
};

class TlsOpener final : public ChannelOpener {
 public:
  // Loads the certificate, key, CA and CRL; the error names the file at fault.
  static std::expected<std::unique_ptr<TlsOpener>, std::string> create(const TlsConfig& config);

  Transport transport() const override { return Transport::tls; }
  std::unique_ptr<ChannelHandshake> begin(int fd) override;
  int handshake_timeout_ms() const override { return kHandshakeTimeoutMs; }

  // Reads the certificate, key, CA and CRL files again (homingd on SIGHUP: a
  // new CRL or certificate without stopping the machine). Connections made
  // from then on use them; open ones keep theirs. On error nothing changes
  // and the error names the file.
  std::expected<void, std::string> reload();

  // The role of the verified peer: client.access and client.identity, or why it gets nothing.
  std::expected<void, std::string> admit(SSL* ssl, ClientInfo& client) const;

 private:
  TlsOpener(tls::SslCtx ctx, TlsConfig config);
  std::shared_ptr<SSL_CTX> context() const;

  const TlsConfig config_;
  mutable std::mutex mutex_;  // ctx_
  std::shared_ptr<SSL_CTX> ctx_;
};

}  // namespace server
