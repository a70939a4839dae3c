#pragma once
// Modbus/TCP Security on an accepted connection: the TLS handshake on the
// connection's own thread (so it never delays another client), bounded by
// kHandshakeTimeoutMs from the connection; the client's certificate verified
// against --tls-ca (and --tls-crl); its role (server/client_role.hpp) decides
// what it may write. A refusal names the client's address, the certificate's
// subject and why.
#include <expected>
#include <memory>
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

 private:
  TlsOpener(tls::SslCtx ctx, std::string default_role) : ctx_(std::move(ctx)), default_role_(std::move(default_role)) {}
  // The role of the verified peer: client.access and client.identity, or why it gets nothing.
  std::expected<void, std::string> admit(SSL* ssl, ClientInfo& client) const;

  tls::SslCtx ctx_;
  std::string default_role_;
};

}  // namespace server
