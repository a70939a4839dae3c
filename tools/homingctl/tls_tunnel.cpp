#include "tls_tunnel.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>

#include "connection.hpp"
#include "host_port.hpp"
#include "tls/context.hpp"

namespace homingctl {
namespace {

bool write_all(int fd, const std::uint8_t* p, std::size_t n) {
  while (n > 0) {
    const ssize_t w = ::send(fd, p, n, MSG_NOSIGNAL);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= static_cast<std::size_t>(w);
  }
  return true;
}

}  // namespace

TlsTunnel::TlsTunnel(const TlsOptions& options) {
  if (options.cert.empty() || options.key.empty() || options.ca.empty())
    throw std::invalid_argument("--tls needs --cert, --key and --ca: this client's certificate and key, and the CA "
                                "that signed the module's certificate");
  auto ctx = tls::client_context(tls::ClientFiles{options.cert, options.key, options.ca});
  if (!ctx) throw std::invalid_argument(ctx.error());
  ctx_ = std::move(*ctx);
  const auto [host, port] = host_and_port(options.address, 802, "--tls");
  auto client = tls::Client::connect(host, port, ctx_.get(), std::chrono::milliseconds(options.timeout_ms));
  if (!client) throw LinkError(fmt::format("tls {}: {}", options.address, client.error()));
  client_.emplace(std::move(*client));
  int pair[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, pair) != 0)
    throw LinkError(fmt::format("socketpair: {}", std::strerror(errno)));
  modbus_end_ = pair[0];
  relay_end_ = pair[1];
  thread_ = std::thread([this] { relay(); });
}

TlsTunnel::~TlsTunnel() {
  stop_ = true;
  if (relay_end_ >= 0) ::shutdown(relay_end_, SHUT_RDWR);  // wakes the relay's poll
  if (thread_.joinable()) thread_.join();
  if (modbus_end_ >= 0) ::close(modbus_end_);
  if (relay_end_ >= 0) ::close(relay_end_);
}

int TlsTunnel::take_modbus_end() {
  const int fd = modbus_end_;
  modbus_end_ = -1;
  return fd;
}

std::string TlsTunnel::failure() const {
  std::lock_guard lock(mutex_);
  return failure_;
}

void TlsTunnel::end(const std::string& why) {
  {
    std::lock_guard lock(mutex_);
    failure_ = why;
  }
  ::shutdown(relay_end_, SHUT_RDWR);  // libmodbus sees the link end
}

// Sends what libmodbus wrote; false when the TLS connection failed.
bool TlsTunnel::to_module(std::span<const std::uint8_t>& pending, bool& want_write) {
  want_write = false;
  while (!pending.empty()) {
    const tls::Io io = client_->session().write(pending);
    if (io.progress == tls::Progress::done) {
      pending = pending.subspan(io.bytes);
    } else if (io.progress == tls::Progress::want_read || io.progress == tls::Progress::want_write) {
      want_write = io.progress == tls::Progress::want_write;
      return true;
    } else {
      end("the module ended the TLS connection: " + client_->session().error());
      return false;
    }
  }
  return true;
}

// Hands libmodbus what the module sent; false when the TLS connection ended.
bool TlsTunnel::to_libmodbus() {
  std::array<std::uint8_t, 4096> buf{};
  for (;;) {
    const tls::Io io = client_->session().read(buf);
    if (io.progress == tls::Progress::done) {
      if (!write_all(relay_end_, buf.data(), io.bytes)) return false;
      continue;
    }
    if (io.progress == tls::Progress::want_read || io.progress == tls::Progress::want_write) return true;
    // In TLS 1.3 a module that refuses this client's certificate says so
    // here, after the client's side of the handshake has finished.
    end("the module ended the TLS connection: " + client_->session().error());
    return false;
  }
}

void TlsTunnel::relay() {
  std::array<std::uint8_t, 4096> up{};
  std::span<const std::uint8_t> pending;
  bool want_write = false;
  while (!stop_) {
    pollfd fds[2] = {{relay_end_, static_cast<short>(pending.empty() ? POLLIN : 0), 0},
                     {client_->fd(), static_cast<short>(POLLIN | (want_write ? POLLOUT : 0)), 0}};
    if (!client_->session().pending() && ::poll(fds, 2, 1000) < 0 && errno != EINTR) break;
    if (fds[0].revents != 0 && pending.empty()) {
      const ssize_t n = ::recv(relay_end_, up.data(), up.size(), MSG_DONTWAIT);
      if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) break;  // libmodbus closed its end
      if (n > 0) pending = std::span(up).first(static_cast<std::size_t>(n));
    }
    if (!pending.empty() && !to_module(pending, want_write)) return;
    if (!to_libmodbus()) return;
  }
  client_->session().close();
}

}  // namespace homingctl
