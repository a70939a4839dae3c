#include "tls/client.hpp"

#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "tls/address.hpp"
#include "tls/context.hpp"

namespace tls {

namespace {

// A non-blocking TCP connection to host:port, established within the deadline.
std::expected<int, std::string> tcp_connect(const std::string& host, int port, Client::Clock::time_point deadline) {
  const auto ip = resolve_ipv4(host);
  if (!ip) return std::unexpected(ip.error());
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr = *ip;
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd < 0) return std::unexpected(std::string("socket: ") + std::strerror(errno));
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0 && errno != EINPROGRESS) {
    const int err = errno;
    ::close(fd);
    return std::unexpected(std::strerror(err));
  }
  int err = 0;
  socklen_t len = sizeof(err);
  if (!wait_for(fd, Progress::want_write, deadline)) err = ETIMEDOUT;
  else ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
  if (err != 0) {
    ::close(fd);
    return std::unexpected(std::strerror(err));
  }
  return fd;
}

// The handshake's failure in words: the server's certificate refused here, or
// what the server (or the network) said.
std::string handshake_failure(const Session& s) {
  if (auto refused = verify_failure(s.ssl()))
    return "the server's certificate (" + refused->subject + ") was not accepted: " + refused->reason +
           (refused->detail.empty() ? "" : " (" + refused->detail + ")");
  return "TLS handshake failed: " + s.error();
}

}  // namespace

std::expected<Client, std::string> Client::connect(const std::string& host, int port, SSL_CTX* ctx,
                                                   std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  auto fd = tcp_connect(host, port, deadline);
  if (!fd) return std::unexpected("cannot connect to " + host + ":" + std::to_string(port) + ": " + fd.error());
  auto session = Session::connect(ctx, *fd, host);
  if (!session) {
    ::close(*fd);
    return std::unexpected(session.error());
  }
  Client client(*fd, std::move(*session));
  for (;;) {
    const Progress p = client.session_.handshake();
    if (p == Progress::done) return client;
    if (p == Progress::closed || p == Progress::failed) return std::unexpected(handshake_failure(client.session_));
    if (!wait_for(*fd, p, deadline))
      return std::unexpected("TLS handshake with " + host + ":" + std::to_string(port) + " timed out");
  }
}

Client::~Client() {
  if (fd_ < 0) return;
  session_.close();
  ::close(fd_);
}

Client::Client(Client&& other) noexcept : fd_(other.fd_), session_(std::move(other.session_)) { other.fd_ = -1; }

std::expected<void, std::string> Client::write_all(std::span<const std::uint8_t> bytes, Clock::time_point deadline) {
  while (!bytes.empty()) {
    const Io io = session_.write(bytes);
    if (io.progress == Progress::done) {
      bytes = bytes.subspan(io.bytes);
      continue;
    }
    if (io.progress == Progress::closed || io.progress == Progress::failed) return std::unexpected(session_.error());
    if (!wait_for(fd_, io.progress, deadline)) return std::unexpected("timed out sending");
  }
  return {};
}

std::expected<std::size_t, std::string> Client::read_some(std::span<std::uint8_t> out, Clock::time_point deadline) {
  for (;;) {
    const Io io = session_.read(out);
    if (io.progress == Progress::done) return io.bytes;
    if (io.progress == Progress::closed || io.progress == Progress::failed) return std::unexpected(session_.error());
    if (!wait_for(fd_, io.progress, deadline)) return std::unexpected("timed out waiting for an answer");
  }
}

std::expected<void, std::string> Client::read_exact(std::span<std::uint8_t> out, Clock::time_point deadline) {
  while (!out.empty()) {
    auto n = read_some(out, deadline);
    if (!n) return std::unexpected(n.error());
    out = out.subspan(*n);
  }
  return {};
}

}  // namespace tls
