#pragma once
// A Modbus/TCP Security client connection with deadlines: the TCP connection,
// the handshake and the bytes, for homingctl, the tests and the benchmark.
#include <chrono>
#include <cstdint>
#include <expected>
#include <span>
#include <string>

#include "tls/session.hpp"

namespace tls {

class Client {
 public:
  using Clock = std::chrono::steady_clock;

  // Connects to host:port (IPv4 address or name) and completes the handshake
  // within `timeout`. The error says which step failed and why, e.g. "the
  // module's certificate was not accepted: certificate has expired".
  static std::expected<Client, std::string> connect(const std::string& host, int port, SSL_CTX* ctx,
                                                    std::chrono::milliseconds timeout);
  ~Client();
  Client(Client&& other) noexcept;
  Client& operator=(Client&&) = delete;
  Client(const Client&) = delete;

  std::expected<void, std::string> write_all(std::span<const std::uint8_t> bytes, Clock::time_point deadline);
  // At least one byte (up to out.size()); an error when the connection ends
  // or the deadline passes first.
  std::expected<std::size_t, std::string> read_some(std::span<std::uint8_t> out, Clock::time_point deadline);
  std::expected<void, std::string> read_exact(std::span<std::uint8_t> out, Clock::time_point deadline);

  int fd() const { return fd_; }
  Session& session() { return session_; }
  const Session& session() const { return session_; }

 private:
  Client(int fd, Session session) : fd_(fd), session_(std::move(session)) {}
  int fd_ = -1;
  Session session_;
};

}  // namespace tls
