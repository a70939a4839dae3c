#pragma once
// Modbus TCP, plain or inside TLS: one thread per connection so that a slow
// or stalled client (or a TLS handshake) never delays the others; frames
// delimited by the MBAP length field as the standard says (libmodbus 3.1.6
// frames TCP by function code and ignores that length, so one odd request
// would desynchronise the stream).
#include <atomic>
#include <cstdint>
#include <expected>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <vector>

#include "byte_channel.hpp"
#include "connection_policy.hpp"
#include "options.hpp"
#include "refusal_log.hpp"
#include "request_handler.hpp"

namespace server {

// What a listener makes of an accepted connection before requests flow, on
// the connection's own thread: plain TCP takes the socket as it is; TLS
// (server/tls_channel.hpp) runs the handshake and learns who the client is.
class ChannelOpener {
 public:
  virtual ~ChannelOpener() = default;
  virtual Transport transport() const = 0;
  // The channel to serve, or why the connection is refused (logged, then closed).
  // May fill in client.access and client.identity.
  virtual std::expected<std::unique_ptr<ByteChannel>, std::string> open(int fd, ClientInfo& client,
                                                                         const std::atomic<bool>& stop) = 0;
};

struct ListenConfig {
  std::string host;
  int port = 0;
  int max_clients = 32;
  int idle_timeout_s = 60;
  // Connection management (server/connection_policy.hpp): addresses that
  // never give way (--privileged) and the cap per address (0: max_clients).
  std::vector<Cidr> privileged;
  int max_per_address = 0;
  int refusal_log_interval_s = 10;  // refused connections: one line per address and reason per interval
};

class TcpServer {
 public:
  // Plain Modbus TCP.
  TcpServer(std::string host, int port, int max_clients, int idle_timeout_s, RequestHandler& handler);
  TcpServer(ListenConfig config, RequestHandler& handler);
  // Each connection through `opener` first (Modbus/TCP Security: a TlsOpener).
  TcpServer(ListenConfig config, RequestHandler& handler, std::unique_ptr<ChannelOpener> opener);
  ~TcpServer();
  TcpServer(const TcpServer&) = delete;
  TcpServer& operator=(const TcpServer&) = delete;

  // Binds and listens; the error names the address and the reason.
  std::expected<void, std::string> listen();
  // Accepts until stop() (call from its own thread).
  void run();
  void stop();
  int active_clients() const { return active_.load(); }
  std::uint64_t refused_clients() const { return refused_.load(); }

 private:
  struct Connection {
    int fd = -1;  // closed by its own thread, under connections_mutex_
    std::thread thread;
    std::atomic<bool> finished{false};
    Peer peer;
    std::string address;
    std::atomic<std::int64_t> last_active_ns{0};
    // Closed to make room for another client: for whom (empty: not).
    std::string closed_for;
  };
  void serve(Connection& connection, ClientInfo info);
  void reap(bool all);
  // Room for a client from `address`; false: refused (logged).
  bool make_room(const Peer& peer, const std::string& address);
  void refuse(const std::string& ip, const std::string& reason, const std::string& line);
  std::string_view name() const;  // "tcp", "tls": for the log

  ListenConfig config_;
  RequestHandler& handler_;
  std::unique_ptr<ChannelOpener> opener_;
  int listen_fd_ = -1;
  std::atomic<bool> stop_{false};
  std::atomic<int> active_{0};
  std::atomic<std::uint64_t> refused_{0};
  std::atomic<std::uint64_t> next_id_{1};
  std::mutex connections_mutex_;
  std::list<Connection> connections_;
  RefusalLog refusals_;  // under connections_mutex_
};

}  // namespace server
