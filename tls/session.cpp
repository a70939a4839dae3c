#include "tls/session.hpp"

#include <arpa/inet.h>
#include <openssl/err.h>
#include <openssl/x509v3.h>
#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "tls/errors.hpp"

namespace tls {
namespace {

std::expected<Ssl, std::string> new_ssl(SSL_CTX* ctx, int fd) {
  ERR_clear_error();
  Ssl ssl(SSL_new(ctx));
  if (!ssl) return std::unexpected("cannot create a TLS session: " + take_errors());
  if (SSL_set_fd(ssl.get(), fd) != 1) return std::unexpected("cannot attach the TLS session: " + take_errors());
  return ssl;
}

bool is_ip(const std::string& host) {
  in_addr v4{};
  in6_addr v6{};
  return inet_pton(AF_INET, host.c_str(), &v4) == 1 || inet_pton(AF_INET6, host.c_str(), &v6) == 1;
}

}  // namespace

std::expected<Session, std::string> Session::accept(SSL_CTX* ctx, int fd) {
  auto ssl = new_ssl(ctx, fd);
  if (!ssl) return std::unexpected(ssl.error());
  SSL_set_accept_state(ssl->get());
  return Session(std::move(*ssl));
}

std::expected<Session, std::string> Session::connect(SSL_CTX* ctx, int fd, const std::string& host) {
  auto ssl = new_ssl(ctx, fd);
  if (!ssl) return std::unexpected(ssl.error());
  SSL* s = ssl->get();
  const bool ok = is_ip(host) ? X509_VERIFY_PARAM_set1_ip_asc(SSL_get0_param(s), host.c_str()) == 1
                              : SSL_set1_host(s, host.c_str()) == 1 && SSL_set_tlsext_host_name(s, host.c_str()) == 1;
  if (!ok) return std::unexpected("cannot ask for a server certificate naming " + host + ": " + take_errors());
  SSL_set_connect_state(s);
  return Session(std::move(*ssl));
}

Progress Session::outcome(int rc) {
  switch (SSL_get_error(ssl_.get(), rc)) {
    case SSL_ERROR_NONE: return Progress::done;
    case SSL_ERROR_WANT_READ: return Progress::want_read;
    case SSL_ERROR_WANT_WRITE: return Progress::want_write;
    case SSL_ERROR_ZERO_RETURN:
      error_ = "closed by the peer";
      return Progress::closed;
    case SSL_ERROR_SYSCALL: {
      const int err = errno;
      error_ = take_errors(err != 0 ? std::strerror(err) : "connection closed");
      closed_ = true;  // no close_notify after a failure
      return err == 0 || err == ECONNRESET || err == EPIPE ? Progress::closed : Progress::failed;
    }
    default:
      error_ = take_errors();
      closed_ = true;
      return Progress::failed;
  }
}

Progress Session::handshake() {
  ERR_clear_error();
  errno = 0;
  return outcome(SSL_do_handshake(ssl_.get()));
}

Io Session::read(std::span<std::uint8_t> out) {
  ERR_clear_error();
  errno = 0;
  std::size_t n = 0;
  if (SSL_read_ex(ssl_.get(), out.data(), out.size(), &n) == 1) return Io{Progress::done, n};
  return Io{outcome(0), 0};
}

Io Session::write(std::span<const std::uint8_t> bytes) {
  ERR_clear_error();
  errno = 0;
  std::size_t n = 0;
  if (SSL_write_ex(ssl_.get(), bytes.data(), bytes.size(), &n) == 1) return Io{Progress::done, n};
  return Io{outcome(0), 0};
}

bool Session::pending() const { return SSL_pending(ssl_.get()) > 0; }

void Session::close() {
  if (closed_ || !ssl_) return;
  closed_ = true;
  ERR_clear_error();
  if (SSL_is_init_finished(ssl_.get())) (void)SSL_shutdown(ssl_.get());
  ERR_clear_error();
}

bool wait_for(int fd, Progress progress, std::chrono::steady_clock::time_point deadline,
              const std::atomic<bool>* stop) {
  const short events = progress == Progress::want_write ? POLLOUT : POLLIN;
  for (;;) {
    if (stop && *stop) return false;
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) return false;
    pollfd p{fd, events, 0};
    // Slices of 200 ms so that a stop request is seen soon.
    const int rc = ::poll(&p, 1, static_cast<int>(std::min<long long>(left, stop ? 200 : left)));
    if (rc > 0) return true;
    if (rc < 0 && errno != EINTR) return false;
  }
}

}  // namespace tls
