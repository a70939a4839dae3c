#pragma once
// Modbus TCP: one thread per connection so that a slow or stalled client never
// delays the others; frames delimited by the MBAP length field as the standard
// says (libmodbus 3.1.6 frames TCP by function code and ignores that length,
// so one odd request would desynchronise the stream).
#include <atomic>
#include <cstdint>
#include <expected>
#include <list>
#include <mutex>
#include <string>
#include <thread>

#include "request_handler.hpp"

namespace server {

class TcpServer {
 public:
  TcpServer(std::string host, int port, int max_clients, int idle_timeout_s, RequestHandler& handler);
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
    int fd = -1;
    std::thread thread;
    std::atomic<bool> finished{false};
  };
  void serve(Connection& connection, ClientInfo info);
  void reap(bool all);

  std::string host_;
  int port_;
  int max_clients_;
  int idle_timeout_s_;
  RequestHandler& handler_;
  int listen_fd_ = -1;
  std::atomic<bool> stop_{false};
  std::atomic<int> active_{0};
  std::atomic<std::uint64_t> refused_{0};
  std::atomic<std::uint64_t> next_id_{1};
  std::mutex connections_mutex_;
  std::list<Connection> connections_;
};

}  // namespace server
