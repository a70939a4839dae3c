#pragma once
// homingctl over Modbus/TCP Security. libmodbus has no TLS, so the link is a
// socket pair: libmodbus uses one end as its TCP socket (modbus_set_socket),
// and a thread relays the bytes of the other end through a TLS session with
// the module. No port is opened. The handshake is done before libmodbus sends
// anything, so a module certificate that is not accepted ends the connect.
#include <atomic>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "tls/client.hpp"
#include "tls/handles.hpp"

namespace homingctl {

struct TlsOptions {
  std::string address;  // HOST[:PORT], port 802 when not given
  std::string cert;     // the client's certificate (its role is in it)
  std::string key;      // its private key
  std::string ca;       // the CA that signed the module's certificate
  int timeout_ms = 3000;  // for the connection and the handshake
};

class TlsTunnel {
 public:
  // Connects and completes the handshake; throws LinkError naming what failed
  // (std::invalid_argument for an unusable certificate or key file).
  explicit TlsTunnel(const TlsOptions& options);
  ~TlsTunnel();
  TlsTunnel(const TlsTunnel&) = delete;
  TlsTunnel& operator=(const TlsTunnel&) = delete;

  // The end libmodbus uses as its socket; libmodbus closes it (modbus_close).
  int take_modbus_end();
  // Why the module or the network ended the TLS connection ("" while it runs).
  std::string failure() const;

 private:
  void relay();
  bool to_module(std::span<const std::uint8_t>& pending, bool& want_write);
  bool to_libmodbus();
  void end(const std::string& why);

  tls::SslCtx ctx_;
  std::optional<tls::Client> client_;
  int modbus_end_ = -1;
  int relay_end_ = -1;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;
  std::string failure_;
  std::thread thread_;
};

}  // namespace homingctl
