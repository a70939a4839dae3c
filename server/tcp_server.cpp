#include "tcp_server.hpp"

#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>

#include "mbap_stream.hpp"

namespace server {
namespace {

// Waits until fd is readable; false on timeout, error, or a stop request.
bool wait_readable(int fd, int timeout_ms, const std::atomic<bool>& stop) {
  int waited = 0;
  while (!stop) {
    const int slice = std::min(200, timeout_ms - waited);
    if (slice <= 0) return false;
    pollfd p{fd, POLLIN, 0};
    const int rc = ::poll(&p, 1, slice);
    if (rc > 0) return true;
    if (rc < 0 && errno != EINTR) return false;
    waited += slice;
  }
  return false;
}

// Buffered reads of one connection: a recv takes whatever has arrived
// (usually the whole request), and poll() is called only when nothing is
// waiting, so a request costs one recv instead of two polls and two recvs.
class Reader {
 public:
  explicit Reader(int fd) : fd_(fd) {}
  bool empty() const { return begin_ == end_; }
  // Reads exactly n bytes (n <= the buffer) before the deadline.
  bool read_exact(std::uint8_t* out, std::size_t n, std::chrono::steady_clock::time_point deadline,
                  const std::atomic<bool>& stop) {
    while (end_ - begin_ < n) {
      if (begin_ > 0) {  // keep the unread bytes at the front
        std::memmove(buf_.data(), buf_.data() + begin_, end_ - begin_);
        end_ -= begin_;
        begin_ = 0;
      }
      const ssize_t r = ::recv(fd_, buf_.data() + end_, buf_.size() - end_, MSG_DONTWAIT);
      if (r > 0) {
        end_ += static_cast<std::size_t>(r);
        continue;
      }
      if (r == 0) return false;
      if (errno == EINTR) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) return false;
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count();
      if (left <= 0 || !wait_readable(fd_, static_cast<int>(left), stop)) return false;
    }
    std::memcpy(out, buf_.data() + begin_, n);
    begin_ += n;
    return true;
  }

 private:
  int fd_;
  std::array<std::uint8_t, 2048> buf_{};
  std::size_t begin_ = 0, end_ = 0;
};

bool send_all(int fd, std::span<const std::uint8_t> bytes) {
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t r = ::send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (r <= 0) {
      if (r < 0 && errno == EINTR) continue;
      return false;
    }
    sent += static_cast<std::size_t>(r);
  }
  return true;
}

constexpr int kFrameTimeoutMs = 1000;  // the rest of a frame must follow its first byte within this

// A connection's socket as the framing loop reads it: the next frame must
// begin within the idle timeout, and the whole frame, not each of its pieces,
// must arrive within the frame timeout.
class SocketStream final : public MbapStream {
 public:
  SocketStream(int fd, int idle_timeout_ms, const std::atomic<bool>& stop)
      : fd_(fd), idle_timeout_ms_(idle_timeout_ms), stop_(stop), reader_(fd) {}
  bool next_frame() override {
    if (reader_.empty() && !wait_readable(fd_, idle_timeout_ms_, stop_)) return false;
    frame_deadline_ = std::chrono::steady_clock::now() + std::chrono::milliseconds(kFrameTimeoutMs);
    return true;
  }
  bool read(std::span<std::uint8_t> out) override {
    return reader_.read_exact(out.data(), out.size(), frame_deadline_, stop_);
  }
  bool send(std::span<const std::uint8_t> frame) override { return send_all(fd_, frame); }

 private:
  int fd_;
  int idle_timeout_ms_;
  const std::atomic<bool>& stop_;
  Reader reader_;
  std::chrono::steady_clock::time_point frame_deadline_{};
};

const char* end_reason(StreamEnd end, bool stopping) {
  switch (end) {
    case StreamEnd::no_next_frame: return stopping ? "server stopping" : "idle timeout (--idle-timeout-s)";
    case StreamEnd::closed: return "closed by the client";
    case StreamEnd::malformed_header: return "malformed MBAP header";
    case StreamEnd::incomplete_frame: return "incomplete frame";
  }
  return "?";
}

}  // namespace

TcpServer::TcpServer(std::string host, int port, int max_clients, int idle_timeout_s, RequestHandler& handler)
    : host_(std::move(host)), port_(port), max_clients_(max_clients), idle_timeout_s_(idle_timeout_s),
      handler_(handler) {}

TcpServer::~TcpServer() {
  stop();
  reap(true);
  if (listen_fd_ >= 0) ::close(listen_fd_);
}

std::expected<void, std::string> TcpServer::listen() {
  // libmodbus opens the listening socket (SO_REUSEADDR, the address parsing).
  modbus_t* ctx = modbus_new_tcp(host_.c_str(), port_);
  if (!ctx) return std::unexpected("--tcp " + host_ + ":" + std::to_string(port_) + ": " + modbus_strerror(errno));
  const int fd = modbus_tcp_listen(ctx, 64);
  const int err = errno;
  modbus_free(ctx);
  if (fd < 0)
    return std::unexpected("--tcp " + host_ + ":" + std::to_string(port_) + ": cannot listen: " + std::strerror(err));
  listen_fd_ = fd;
  return {};
}

void TcpServer::run() {
  while (!stop_) {
    pollfd p{listen_fd_, POLLIN, 0};
    const int rc = ::poll(&p, 1, 200);
    reap(false);
    if (rc <= 0) continue;
    sockaddr_in peer{};
    socklen_t len = sizeof(peer);
    const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &len, SOCK_CLOEXEC);
    if (fd < 0) continue;
    char ip[INET_ADDRSTRLEN] = "?";
    ::inet_ntop(AF_INET, &peer.sin_addr, ip, sizeof(ip));
    const std::string address = std::string(ip) + ":" + std::to_string(ntohs(peer.sin_port));
    if (active_.load() >= max_clients_) {
      ++refused_;
      spdlog::warn("tcp: refused {}: {} clients connected, the maximum (--max-clients)", address, max_clients_);
      ::close(fd);
      continue;
    }
    const int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    ++active_;
    ClientInfo info{next_id_++, Transport::tcp, address};
    spdlog::info("tcp: client {} connected ({} active)", address, active_.load());
    std::lock_guard lock(connections_mutex_);
    Connection& c = connections_.emplace_back();
    c.fd = fd;
    c.thread = std::thread([this, &c, info] { serve(c, info); });
  }
}

void TcpServer::serve(Connection& c, ClientInfo info) {
  SocketStream stream(c.fd, idle_timeout_s_ * 1000, stop_);
  const StreamEnd end = serve_mbap_stream(stream, handler_, info);
  ::shutdown(c.fd, SHUT_RDWR);
  ::close(c.fd);
  --active_;
  spdlog::info("tcp: client {} disconnected: {}", info.address, end_reason(end, stop_));
  c.finished = true;
}

void TcpServer::reap(bool all) {
  std::lock_guard lock(connections_mutex_);
  for (auto it = connections_.begin(); it != connections_.end();) {
    if (all || it->finished) {
      if (it->thread.joinable()) it->thread.join();
      it = connections_.erase(it);
    } else {
      ++it;
    }
  }
}

void TcpServer::stop() { stop_ = true; }

}  // namespace server
