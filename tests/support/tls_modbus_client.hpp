#pragma once
// A Modbus/TCP Security client made here on OpenSSL (tls/client.hpp), without
// libmodbus: MBAP frames built by hand, one request in flight, registers by
// the register table's names (module unit 1, simulator unit 247).
#include <chrono>
#include <cstdint>
#include <expected>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tests/support/test_pki.hpp"
#include "tls/client.hpp"
#include "tls/handles.hpp"

namespace test_support {

class TlsModbusClient {
 public:
  // The TCP connection and the handshake; the error says why they failed.
  static std::expected<TlsModbusClient, std::string> connect(
      int port, const TlsIdentity& identity, std::chrono::milliseconds timeout = std::chrono::seconds(5));
  // With a context the test made (tls::client_context, then adjusted).
  static std::expected<TlsModbusClient, std::string> connect(
      int port, tls::SslCtx ctx, std::chrono::milliseconds timeout = std::chrono::seconds(5));
  // The protocol version agreed: TLS1_2_VERSION, TLS1_3_VERSION.
  int protocol_version() const { return SSL_version(client_.session().ssl()); }
  // The session, for what the test inspects (the suite agreed).
  SSL* ssl() const { return client_.session().ssl(); }

  // One request: the reply PDU, or why none came (the TLS alert the module
  // sent, a closed connection, a timeout).
  std::expected<std::vector<std::uint8_t>, std::string> transaction(
      std::uint8_t unit, std::span<const std::uint8_t> pdu,
      std::chrono::milliseconds timeout = std::chrono::seconds(3));

  // Every request sent before any reply is read: in one TLS record, or one
  // record each. The replies' transaction ids and PDUs as they came back.
  std::expected<std::vector<std::pair<std::uint16_t, std::vector<std::uint8_t>>>, std::string> pipeline(
      std::uint8_t unit, const std::vector<std::vector<std::uint8_t>>& pdus, bool one_record,
      std::chrono::milliseconds timeout = std::chrono::seconds(3));

  // The raw value of a named register; throws on an exception or a link failure.
  std::int64_t read(std::string_view name);
  // Coils FC 5, holding registers FC 16: 0, the Modbus exception code, or -1
  // when no answer came (last_error() says why).
  int write(std::string_view name, std::int64_t raw);
  const std::string& last_error() const { return last_error_; }

 private:
  TlsModbusClient(tls::SslCtx ctx, tls::Client client) : ctx_(std::move(ctx)), client_(std::move(client)) {}
  tls::SslCtx ctx_;
  tls::Client client_;
  std::uint16_t transaction_id_ = 1;
  std::string last_error_;
};

}  // namespace test_support
