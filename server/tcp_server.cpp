#include "tcp_server.hpp"

#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "channel_stream.hpp"
#include "mbap_stream.hpp"

namespace server {
namespace {

// Plain Modbus TCP: the socket as it is.
class PlainOpener final : public ChannelOpener {
 public:
  Transport transport() const override { return Transport::tcp; }
  std::expected<std::unique_ptr<ByteChannel>, std::string> open(int fd, ClientInfo&,
                                                                 const std::atomic<bool>&) override {
    return std::make_unique<SocketChannel>(fd);
  }
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
    : TcpServer(ListenConfig{std::move(host), port, max_clients, idle_timeout_s}, handler,
                std::make_unique<PlainOpener>()) {}

TcpServer::TcpServer(ListenConfig config, RequestHandler& handler, std::unique_ptr<ChannelOpener> opener)
    : config_(std::move(config)), handler_(handler), opener_(std::move(opener)) {}

TcpServer::~TcpServer() {
  stop();
  reap(true);
  if (listen_fd_ >= 0) ::close(listen_fd_);
}

std::string_view TcpServer::name() const { return transport_name(opener_->transport()); }

std::expected<void, std::string> TcpServer::listen() {
  const std::string where = "--" + std::string(name()) + " " + config_.host + ":" + std::to_string(config_.port);
  // libmodbus opens the listening socket (SO_REUSEADDR, the address parsing).
  modbus_t* ctx = modbus_new_tcp(config_.host.c_str(), config_.port);
  if (!ctx) return std::unexpected(where + ": " + modbus_strerror(errno));
  const int fd = modbus_tcp_listen(ctx, 64);
  const int err = errno;
  modbus_free(ctx);
  if (fd < 0) return std::unexpected(where + ": cannot listen: " + std::strerror(err));
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
    if (active_.load() >= config_.max_clients) {
      ++refused_;
      spdlog::warn("{}: refused {}: {} clients connected, the maximum (--max-clients)", name(), address,
                   config_.max_clients);
      ::close(fd);
      continue;
    }
    const int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    ++active_;
    ClientInfo info(next_id_++, opener_->transport(), address);
    std::lock_guard lock(connections_mutex_);
    Connection& c = connections_.emplace_back();
    c.fd = fd;
    c.thread = std::thread([this, &c, info] { serve(c, info); });
  }
}

void TcpServer::serve(Connection& c, ClientInfo info) {
  if (auto channel = opener_->open(c.fd, info, stop_)) {
    spdlog::info("{}: client {}{}{} connected ({} active)", name(), info.address, info.identity.empty() ? "" : " ",
                 info.identity, active_.load());
    ChannelStream stream(**channel, config_.idle_timeout_s * 1000, stop_);
    const StreamEnd end = serve_mbap_stream(stream, handler_, info);
    channel->reset();  // a TLS channel says goodbye on the socket
    spdlog::info("{}: client {} disconnected: {}", name(), info.address, end_reason(end, stop_));
  } else {
    spdlog::warn("{}: refused {}: {}", name(), info.address, channel.error());
  }
  ::shutdown(c.fd, SHUT_RDWR);
  ::close(c.fd);
  --active_;
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
