#include "tcp_server.hpp"

#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <vector>

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

std::int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Notes when its connection last sent a request (the least recently active
// connection is the one that gives way when the server is full) and hands
// everything on.
class ActivityHandler final : public RequestHandler {
 public:
  ActivityHandler(RequestHandler& inner, std::atomic<std::int64_t>& last_active_ns)
      : inner_(inner), last_active_ns_(last_active_ns) {}
  Reply handle(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client) override {
    last_active_ns_.store(steady_ns());
    return inner_.handle(unit, pdu, client);
  }
  void disconnected(const ClientInfo& client) override { inner_.disconnected(client); }
  void bus_event(Transport transport, BusEvent event) override { inner_.bus_event(transport, event); }

 private:
  RequestHandler& inner_;
  std::atomic<std::int64_t>& last_active_ns_;
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
    : TcpServer(
          [&] {
            ListenConfig config;
            config.host = std::move(host);
            config.port = port;
            config.max_clients = max_clients;
            config.idle_timeout_s = idle_timeout_s;
            return config;
          }(),
          handler, std::make_unique<PlainOpener>()) {}

TcpServer::TcpServer(ListenConfig config, RequestHandler& handler)
    : TcpServer(std::move(config), handler, std::make_unique<PlainOpener>()) {}

TcpServer::TcpServer(ListenConfig config, RequestHandler& handler, std::unique_ptr<ChannelOpener> opener)
    : config_(std::move(config)),
      handler_(handler),
      opener_(std::move(opener)),
      refusals_("connections", std::chrono::seconds(config_.refusal_log_interval_s),
                [](spdlog::level::level_enum level, const std::string& line) { spdlog::log(level, "{}", line); }) {}

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
    {
      std::lock_guard lock(connections_mutex_);
      refusals_.flush(std::chrono::steady_clock::now());
    }
    if (rc <= 0) continue;
    sockaddr_in peer{};
    socklen_t len = sizeof(peer);
    const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &len, SOCK_CLOEXEC);
    if (fd < 0) continue;
    char ip[INET_ADDRSTRLEN] = "?";
    ::inet_ntop(AF_INET, &peer.sin_addr, ip, sizeof(ip));
    const std::string address = std::string(ip) + ":" + std::to_string(ntohs(peer.sin_port));
    const bool privileged = std::any_of(config_.privileged.begin(), config_.privileged.end(),
                                        [&](const Cidr& c) { return c.contains(address); });
    const Peer who{ntohl(peer.sin_addr.s_addr), privileged};
    std::lock_guard lock(connections_mutex_);
    if (!make_room(who, address)) {
      ::close(fd);
      continue;
    }
    const int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    ++active_;
    ClientInfo info(next_id_++, opener_->transport(), address);
    Connection& c = connections_.emplace_back();
    c.fd = fd;
    c.peer = who;
    c.address = address;
    c.last_active_ns = steady_ns();
    c.thread = std::thread([this, &c, info] { serve(c, info); });
  }
  std::lock_guard lock(connections_mutex_);
  refusals_.flush_all(std::chrono::steady_clock::now());
}

void TcpServer::refuse(const std::string& ip, const std::string& reason, const std::string& line) {
  ++refused_;
  refusals_.refused(std::string(name()) + " " + ip, reason, spdlog::level::warn, line, std::chrono::steady_clock::now());
}

bool TcpServer::make_room(const Peer& peer, const std::string& address) {
  std::vector<Connection*> open;
  std::vector<HeldConnection> held;
  for (Connection& c : connections_) {
    if (c.finished || c.fd < 0 || !c.closed_for.empty()) continue;
    open.push_back(&c);
    held.push_back({c.peer, c.last_active_ns.load()});
  }
  const Admission a = admit(held, peer, ConnectionLimits{config_.max_clients, config_.max_per_address});
  const std::string ip = address.substr(0, address.rfind(':'));
  switch (a.kind) {
    case Admission::Kind::admit: return true;
    case Admission::Kind::refuse_address_cap:
      refuse(ip, "per-address cap (--max-clients-per-address)",
             fmt::format("{}: refused {}: {} holds {} connections, the maximum per address (--max-clients-per-address)",
                         name(), address, ip, a.address_count));
      return false;
    case Admission::Kind::refuse_full:
      refuse(ip, "server full (--max-clients)",
             fmt::format("{}: refused {}: {} clients connected, the maximum (--max-clients); no connection may give way "
                         "to it (the others are privileged, or no address holds two more than its own)",
                         name(), address, config_.max_clients));
      return false;
    case Admission::Kind::admit_closing: {
      Connection& victim = *open[a.close];
      victim.closed_for = address;
      ::shutdown(victim.fd, SHUT_RDWR);  // its thread sees the end and closes it
      const double idle_s = static_cast<double>(steady_ns() - victim.last_active_ns.load()) / 1e9;
      spdlog::warn("{}: closed {} (the least recently active connection that may give way: last request {:.1f} s ago) "
                   "to make room for {}{}: {} clients connected, the maximum (--max-clients)",
                   name(), victim.address, idle_s, address, peer.privileged ? " (privileged)" : "",
                   config_.max_clients);
      return true;
    }
  }
  return false;
}

void TcpServer::serve(Connection& c, ClientInfo info) {
  if (auto channel = opener_->open(c.fd, info, stop_)) {
    spdlog::info("{}: client {}{}{} connected ({} active)", name(), info.address, info.identity.empty() ? "" : " ",
                 info.identity, active_.load());
    ChannelStream stream(**channel, config_.idle_timeout_s * 1000, stop_);
    ActivityHandler handler(handler_, c.last_active_ns);
    const StreamEnd end = serve_mbap_stream(stream, handler, info);
    channel->reset();  // a TLS channel says goodbye on the socket
    std::string closed_for;
    {
      std::lock_guard lock(connections_mutex_);
      closed_for = c.closed_for;
    }
    if (closed_for.empty())
      spdlog::info("{}: client {} disconnected: {}", name(), info.address, end_reason(end, stop_));
    else
      spdlog::info("{}: client {} disconnected: closed to make room for {}", name(), info.address, closed_for);
  } else {
    spdlog::warn("{}: refused {}: {}", name(), info.address, channel.error());
  }
  {
    // Under the lock: make_room never shuts down a descriptor number that
    // another connection may reuse.
    std::lock_guard lock(connections_mutex_);
    ::shutdown(c.fd, SHUT_RDWR);
    ::close(c.fd);
    c.fd = -1;
  }
  --active_;
  c.finished = true;
}

void TcpServer::reap(bool all) {
  // Joined outside the lock: a connection's thread takes it to close its socket.
  std::list<Connection> done;
  {
    std::lock_guard lock(connections_mutex_);
    for (auto it = connections_.begin(); it != connections_.end();) {
      const auto next = std::next(it);
      if (all || it->finished) done.splice(done.end(), connections_, it);
      it = next;
    }
  }
  for (Connection& c : done)
    if (c.thread.joinable()) c.thread.join();
}

void TcpServer::stop() { stop_ = true; }

}  // namespace server
