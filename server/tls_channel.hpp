#pragma once
// Modbus/TCP Security on an accepted connection: the TLS handshake on the
// connection's own thread (so it never delays another client), bounded by
// kHandshakeTimeoutMs from the connection; the client's certificate verified
// against --tls-ca (and --tls-crl); its role (server/client_role.hpp) decides
// what it may write. A refusal names the client's address, the certificate's
// subject and why.
#include <expected>
#include <memory>
#include <mutex>
#include <string>

#include "tcp_server.hpp"
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
  std::expected<std::unique_ptr<ByteChannel>, std::string> open(int fd, ClientInfo& client,
                                                                 const std::atomic<bool>& stop) override;

  // Reads the certificate, key, CA and CRL files again (homingd on SIGHUP: a
  // new CRL or certificate without stopping the machine). Connections made
  // from then on use them; open ones keep theirs. On error nothing changes
  // and the error names the file.
  std::expected<void, std::string> reload();

 private:
  TlsOpener(tls::SslCtx ctx, TlsConfig config);
  // The role of the verified peer: client.access and client.identity, or why it gets nothing.
  std::expected<void, std::string> admit(SSL* ssl, ClientInfo& client) const;
  std::shared_ptr<SSL_CTX> context() const;

  const TlsConfig config_;
  mutable std::mutex mutex_;  // ctx_
  std::shared_ptr<SSL_CTX> ctx_;
};

}  // namespace server
