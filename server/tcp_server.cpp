#include "tcp_server.hpp"
#include "thread_name.hpp"

#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "tcp_connection.hpp"

namespace server {

namespace {
// One sequence for every listener (plain TCP and TLS): a client id names one
// connection in the whole daemon, for the jog buttons (jog_buttons.hpp) above all.
std::uint64_t next_client_id() {
  static std::atomic<std::uint64_t> next{1};
  return next++;
}
}  // namespace
namespace {

// Plain Modbus TCP: the socket as it is.
class PlainHandshake final : public ChannelHandshake {
 public:
  explicit PlainHandshake(int fd) : fd_(fd) {}
  OpenStep step(ClientInfo&) override { return OpenStep::opened(); }
  std::unique_ptr<ByteChannel> channel() override { return std::make_unique<SocketChannel>(fd_); }

 private:
  int fd_;
};

class PlainOpener final : public ChannelOpener {
 public:
  Transport transport() const override { return Transport::tcp; }
  std::unique_ptr<ChannelHandshake> begin(int fd) override { return std::make_unique<PlainHandshake>(fd); }
};

int loop_count(int configured) {
  if (configured > 0) return configured;
  const unsigned cores = std::thread::hardware_concurrency();
  return cores == 0 ? 1 : static_cast<int>(cores);
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
                [](spdlog::level::level_enum level, const std::string& line) { spdlog::log(level, "{}", line); }),
      // One request in flight per connection at most: never more threads than that.
      workers_(static_cast<std::size_t>(std::max(1, config_.max_clients)), std::string(name()) + "-write") {
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake_fd_ < 0) throw std::runtime_error(std::string("tcp server: eventfd: ") + std::strerror(errno));
  const int loops = loop_count(config_.event_loops);
  for (int i = 0; i < loops; ++i)
    loops_.push_back(std::make_unique<EventLoop>(
        EventLoop::Shared{handler_, workers_, connections_mutex_, active_, stop_, name(),
                          std::chrono::microseconds(config_.poll_us),
                          [this](const std::string& address, const std::string& reason) {
                            refused_after_accept(address, reason);
                          }}));
}

TcpServer::~TcpServer() {
  stop();
  workers_.join();  // before the loops go: a request running posts its answer to its loop
  reap(true);
  if (listen_fd_ >= 0) ::close(listen_fd_);
  ::close(wake_fd_);
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
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < loops_.size(); ++i)
    threads.emplace_back([this, i] {
      name_this_thread(fmt::format("{}-loop-{}", name(), i));
      loops_[i]->run();
    });
  while (!stop_) {
    bool counting = false;
    {
      std::lock_guard lock(connections_mutex_);
      counting = refusals_.holds_clients();
    }
    // Idle, this thread sleeps until a client connects or stop(); while
    // refusals are counted it looks every 200 ms to write their summary.
    pollfd p[2] = {{listen_fd_, POLLIN, 0}, {wake_fd_, POLLIN, 0}};
    const int rc = ::poll(p, 2, counting ? 200 : -1);
    if (rc > 0 && (p[1].revents & POLLIN)) {
      eventfd_t drained = 0;
      (void)::eventfd_read(wake_fd_, &drained);
    }
    reap(false);
    {
      std::lock_guard lock(connections_mutex_);
      refusals_.flush(std::chrono::steady_clock::now());
    }
    if (rc <= 0 || !(p[0].revents & POLLIN)) continue;
    sockaddr_in peer{};
    socklen_t len = sizeof(peer);
    const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &len, SOCK_CLOEXEC | SOCK_NONBLOCK);
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
    ConnectionEntry& entry = connections_.emplace_back();
    entry.fd = fd;
    entry.peer = who;
    entry.address = address;
    entry.last_active_ns = steady_now_ns();
    auto connection = std::make_unique<TcpConnection>(
        fd, ClientInfo(next_client_id(), opener_->transport(), address), opener_->begin(fd), opener_->handshake_timeout_ms(),
        config_.idle_timeout_s * 1000, std::chrono::steady_clock::now());
    quietest_loop().adopt(entry, std::move(connection));
  }
  for (auto& loop : loops_) loop->wake();
  for (std::thread& t : threads) t.join();
  std::lock_guard lock(connections_mutex_);
  refusals_.flush_all(std::chrono::steady_clock::now());
}

EventLoop& TcpServer::quietest_loop() {
  return **std::min_element(loops_.begin(), loops_.end(),
                            [](const auto& a, const auto& b) { return a->connections() < b->connections(); });
}

// From an event loop: a failed or missing TLS handshake. A scanner, a health
// check on the port or an HMI left with an expired certificate repeats it
// for as long as it runs: one line, then counts per interval.
void TcpServer::refused_after_accept(const std::string& address, const std::string& reason) {
  {
    std::lock_guard lock(connections_mutex_);
    refuse(address.substr(0, address.rfind(':')), reason, fmt::format("{}: refused {}: {}", name(), address, reason));
  }
  ::eventfd_write(wake_fd_, 1);  // the acceptor writes the counts when the interval ends
}

void TcpServer::refuse(const std::string& ip, const std::string& reason, const std::string& line) {
  ++refused_;
  refusals_.refused(std::string(name()) + " " + ip, reason, spdlog::level::warn, line, std::chrono::steady_clock::now());
}

bool TcpServer::make_room(const Peer& peer, const std::string& address) {
  std::vector<ConnectionEntry*> open;
  std::vector<HeldConnection> held;
  for (ConnectionEntry& c : connections_) {
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
      ConnectionEntry& victim = *open[a.close];
      victim.closed_for = address;
      ::shutdown(victim.fd, SHUT_RDWR);  // its loop sees the end and closes it
      const double idle_s = static_cast<double>(steady_now_ns() - victim.last_active_ns.load()) / 1e9;
      spdlog::warn("{}: closed {} (the least recently active connection that may give way: last request {:.1f} s ago) "
                   "to make room for {}{}: {} clients connected, the maximum (--max-clients)",
                   name(), victim.address, idle_s, address, peer.privileged ? " (privileged)" : "",
                   config_.max_clients);
      return true;
    }
  }
  return false;
}

void TcpServer::reap(bool all) {
  std::lock_guard lock(connections_mutex_);
  std::erase_if(connections_, [all](const ConnectionEntry& c) { return all || c.finished; });
}

void TcpServer::stop() {
  stop_ = true;
  const std::uint64_t one = 1;
  (void)!::write(wake_fd_, &one, sizeof one);  // the acceptor's poll
  for (auto& loop : loops_) loop->wake();
}

}  // namespace server
