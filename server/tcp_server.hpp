#pragma once
// Modbus TCP, plain or inside TLS, served by a few event loops
// (server/event_loop.hpp): as many as the machine has cores, each with epoll
// over non-blocking sockets, the connections spread over them. A slow,
// stalled or garbage-sending client (or a TLS handshake) never delays
// another: nothing in a loop waits, and requests that may wait (writes) run
// on RequestWorkers. This thread accepts and decides who gets a connection
// (server/connection_policy.hpp).
#include <atomic>
#include <cstdint>
#include <expected>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "channel_opener.hpp"
#include "connection_policy.hpp"
#include "event_loop.hpp"
#include "options.hpp"
#include "refusal_log.hpp"
#include "request_handler.hpp"
#include "request_workers.hpp"

namespace server {

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
  int event_loops = 0;              // 0: one per core
  int poll_us = kDefaultPollUs;     // the longest a loop polls before sleeping (server/poll_window.hpp); 0: never
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
  // Accepts and serves until stop() (call from its own thread); returns once
  // every connection is closed.
  void run();
  void stop();
  int active_clients() const { return active_.load(); }
  std::uint64_t refused_clients() const { return refused_.load(); }

 private:
  // Room for a client from `address`; false: refused (logged).
  bool make_room(const Peer& peer, const std::string& address);
  void refuse(const std::string& ip, const std::string& reason, const std::string& line);
  void reap(bool all);
  EventLoop& quietest_loop();
  std::string_view name() const;  // "tcp", "tls": for the log

  ListenConfig config_;
  RequestHandler& handler_;
  std::unique_ptr<ChannelOpener> opener_;
  int listen_fd_ = -1;
  int wake_fd_ = -1;  // stop() wakes the acceptor
  std::atomic<bool> stop_{false};
  std::atomic<int> active_{0};
  std::atomic<std::uint64_t> refused_{0};
  std::mutex connections_mutex_;
  std::list<ConnectionEntry> connections_;  // under connections_mutex_
  RefusalLog refusals_;                     // under connections_mutex_
  void refused_after_accept(const std::string& address, const std::string& reason);
  RequestWorkers workers_;
  std::vector<std::unique_ptr<EventLoop>> loops_;
};

}  // namespace server
