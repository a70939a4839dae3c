#include "tls/session.hpp"

#include <arpa/inet.h>
#include <openssl/err.h>
#include <openssl/x509v3.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "tls/errors.hpp"

namespace tls {
namespace {

// OpenSSL's own socket BIO writes with write(), which raises SIGPIPE on a
// connection the peer has closed and would end a process that does not ignore
// it (homingctl, the tests). This one sends with MSG_NOSIGNAL: a closed
// connection is an error to report like any other.
int bio_write(BIO* bio, const char* data, int length) {
  BIO_clear_retry_flags(bio);
  const ssize_t n = ::send(static_cast<int>(BIO_get_fd(bio, nullptr)), data, static_cast<std::size_t>(length),
                           MSG_NOSIGNAL);
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) BIO_set_retry_write(bio);
  return static_cast<int>(n);
}

int bio_read(BIO* bio, char* data, int length) {
  BIO_clear_retry_flags(bio);
  const ssize_t n = ::recv(static_cast<int>(BIO_get_fd(bio, nullptr)), data, static_cast<std::size_t>(length), 0);
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) BIO_set_retry_read(bio);
  if (n == 0) BIO_set_flags(bio, BIO_FLAGS_IN_EOF);  // as OpenSSL's socket BIO: the peer closed
  return static_cast<int>(n);
}

int bio_puts(BIO* bio, const char* text) { return bio_write(bio, text, static_cast<int>(std::strlen(text))); }

// The socket BIO's controls (the descriptor, flush) with our read and write.
const BIO_METHOD* nosignal_socket() {
  static BIO_METHOD* const method = [] {
    BIO_METHOD* m = BIO_meth_new(BIO_get_new_index() | BIO_TYPE_SOURCE_SINK | BIO_TYPE_DESCRIPTOR,
                                 "socket without SIGPIPE");
    const BIO_METHOD* base = BIO_s_socket();
    BIO_meth_set_write(m, bio_write);
    BIO_meth_set_read(m, bio_read);
    BIO_meth_set_puts(m, bio_puts);
    BIO_meth_set_ctrl(m, BIO_meth_get_ctrl(base));
    BIO_meth_set_create(m, BIO_meth_get_create(base));
    BIO_meth_set_destroy(m, BIO_meth_get_destroy(base));
    return m;
  }();
  return method;
}

std::expected<Ssl, std::string> new_ssl(SSL_CTX* ctx, int fd) {
  ERR_clear_error();
  Ssl ssl(SSL_new(ctx));
  if (!ssl) return std::unexpected("cannot create a TLS session: " + take_errors());
  BIO* bio = BIO_new(nosignal_socket());
  if (!bio) return std::unexpected("cannot attach the TLS session: " + take_errors());
  BIO_set_fd(bio, fd, BIO_NOCLOSE);
  SSL_set_bio(ssl.get(), bio, bio);  // the session owns it now
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

bool Session::pending() const { return SSL_pending(ssl_.get()) > 0 || SSL_has_pending(ssl_.get()) == 1; }

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
