#pragma once
// One event loop of a Modbus/TCP listener (server/tcp_server.hpp): epoll over
// the non-blocking sockets of the connections it was given, each a
// TcpConnection state machine stepped when its socket is ready or its
// deadline passes. A listener runs as many loops as the machine has cores
// and spreads its connections over them. Nothing in a loop waits: a TLS
// handshake is a state, and a request that may wait goes to the service's
// settings writer (a write of the module unit) or runs on RequestWorkers,
// and its reply comes back through the loop's inbox.
#include <atomic>
#include <functional>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include <sys/epoll.h>

#include "connection_policy.hpp"
#include "poll_window.hpp"
#include "request_handler.hpp"
#include "request_workers.hpp"
#include "tcp_connection.hpp"

namespace server {

// What the listener's admission (server/connection_policy.hpp) knows of a
// connection; shared by the acceptor and the connection's loop.
struct ConnectionEntry {
  int fd = -1;  // closed by its loop, under the listener's registry mutex
  Peer peer;
  std::string address;
  std::atomic<std::int64_t> last_active_ns{0};  // steady clock: the last request (or the accept)
  std::string closed_for;                       // under the registry mutex: closed to make room for whom
  std::atomic<bool> finished{false};            // closed: the acceptor may forget it
};

std::int64_t steady_now_ns();

class EventLoop {
 public:
  struct Shared {
    RequestHandler& handler;
    RequestWorkers& workers;
    std::mutex& registry_mutex;
    std::atomic<int>& active;
    const std::atomic<bool>& stop;
    std::string_view name;  // "tcp", "tls": for the log
    std::chrono::microseconds poll_longest{0};  // server/poll_window.hpp; 0: never poll
    // A connection refused after it was accepted (a TLS handshake that failed
    // or never came): given to the server's refusal log, which writes the
    // first of a client's refusals for a reason whole and counts the rest.
    // Unset: each is one warn line.
    std::function<void(const std::string& address, const std::string& reason)> refused{};
  };
  explicit EventLoop(Shared shared);
  ~EventLoop();
  EventLoop(const EventLoop&) = delete;
  EventLoop& operator=(const EventLoop&) = delete;

  // From the acceptor: the loop takes the connection over.
  void adopt(ConnectionEntry& entry, std::unique_ptr<TcpConnection> connection);
  // Serves until stop, then closes what it holds.
  void run();
  void wake();
  int connections() const { return held_.load(); }
  struct PollCounts {
    std::uint64_t polls = 0;
    std::uint64_t caught = 0;
  };
  PollCounts poll_counts() const { return {polls_.load(), polls_caught_.load()}; }

 private:
  struct Slot {
    ConnectionEntry* entry = nullptr;
    std::unique_ptr<TcpConnection> connection;
    std::uint32_t events = 0;  // registered with epoll (0: not registered)
    bool announced = false;    // "connected" logged
    std::uint64_t turn = 0;    // the last turn of the loop that stepped it
  };
  struct Answer {
    std::uint64_t id;
    Reply reply;
  };
  void take_inbox(std::vector<std::uint64_t>& ready);
  void step(std::uint64_t id, Slot& slot, std::vector<std::uint64_t>& again);
  void note_deadline(const Slot& slot);
  // Adds to ready the connections whose deadline has passed, once the earliest has.
  void expire_due(std::chrono::steady_clock::time_point now, std::vector<std::uint64_t>& ready);
  void watch(std::uint64_t id, Slot& slot, std::uint32_t events);
  void send_off(std::uint64_t id, Slot& slot);
  void post_answer(std::uint64_t id, Reply reply);  // from another thread
  void close(std::uint64_t id, Slot& slot, bool stopping);
  int wait_ms(bool again) const;
  // Waits for events (polling first after a turn with work); their count.
  int wait_for_events(std::span<epoll_event> events, bool again);

  Shared shared_;
  int epoll_fd_ = -1;
  int wake_fd_ = -1;
  std::atomic<int> held_{0};
  std::uint64_t next_id_ = 1;
  std::uint64_t turn_ = 0;  // counts the loop's wake-ups
  PollWindow poll_;
  // The last turn served a connection that stays on the loop. A request sent
  // off the loop is not reason to poll: its answer waits for a commit or the
  // control loop, which need the core the polling would take.
  bool worked_ = false;
  std::atomic<std::uint64_t> polls_{0};         // waits that began with polling
  std::atomic<std::uint64_t> polls_caught_{0};  // of them, ended by what the polling caught
  std::unordered_map<std::uint64_t, Slot> slots_;  // the loop's thread only
  // No connection's deadline is earlier (the loop's thread only). It may be
  // earlier than the true earliest, never later: only a step moves a
  // connection's deadline (later, or sooner: a reply or a frame begun), and
  // note_deadline takes the new one.
  std::optional<std::chrono::steady_clock::time_point> next_due_;

  std::mutex inbox_mutex_;
  std::vector<std::pair<ConnectionEntry*, std::unique_ptr<TcpConnection>>> arrivals_;
  std::vector<Answer> answers_;
  // An answer's wake-up is on its way (an eventfd write the loop has not yet
  // followed with take_inbox): the answers posted meanwhile ride on it.
  bool answer_wake_sent_ = false;
};

}  // namespace server
