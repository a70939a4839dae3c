// One TCP event loop (server/event_loop.hpp) over Unix socket pairs: the
// connections that became ready are served in the order their requests
// arrived, not in the order they connected, and a loop that polls before it
// sleeps (server/poll_window.hpp) stops polling when its clients go quiet.
#include <catch2/catch.hpp>
#include <fcntl.h>
#include <pthread.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "server/event_loop.hpp"

using namespace std::chrono_literals;

namespace {

class Plain final : public server::ChannelHandshake {
 public:
  explicit Plain(int fd) : fd_(fd) {}
  server::OpenStep step(server::ClientInfo&) override { return server::OpenStep::opened(); }
  std::unique_ptr<server::ByteChannel> channel() override { return std::make_unique<server::SocketChannel>(fd_); }

 private:
  int fd_;
};

// Notes which connection each request came from; the second request of
// connection 0 holds the loop until the test lets it go.
class Recorder final : public server::RequestHandler {
 public:
  server::Reply handle(std::uint8_t, std::span<const std::uint8_t> pdu, const server::ClientInfo& client) override {
    std::unique_lock lock(mutex_);
    order_.push_back(client.id);
    changed_.notify_all();
    if (client.id == 0 && ++zero_seen_ == 2) changed_.wait_for(lock, 5s, [&] { return released_; });
    return server::Reply{true, {pdu[0], 0}};
  }
  void disconnected(const server::ClientInfo&) override {}

  bool wait_for_requests(std::size_t n) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, 5s, [&] { return order_.size() >= n; });
  }
  void release() {
    std::lock_guard lock(mutex_);
    released_ = true;
    changed_.notify_all();
  }
  std::vector<std::uint64_t> order() {
    std::lock_guard lock(mutex_);
    return order_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<std::uint64_t> order_;
  bool released_ = false;
  int zero_seen_ = 0;
};

void send_read(int fd, std::uint8_t tid) {
  const std::array<std::uint8_t, 12> frame{0, tid, 0, 0, 0, 6, 1, 0x03, 0, 0, 0, 1};
  REQUIRE(::send(fd, frame.data(), frame.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(frame.size()));
}

void take_reply(int fd) {
  std::array<std::uint8_t, 9> reply{};  // MBAP + function + one byte
  REQUIRE(::recv(fd, reply.data(), reply.size(), MSG_WAITALL) == static_cast<ssize_t>(reply.size()));
}

// Runs the loop on its own thread; stops it however the test ends.
struct Running {
  server::EventLoop& loop;
  std::atomic<bool>& stop;
  std::thread runner{[this] { loop.run(); }};
  ~Running() {
    stop = true;
    loop.wake();
    runner.join();
  }
  // CPU time the loop's thread has used so far.
  std::chrono::nanoseconds cpu_time() {
    clockid_t clock{};
    REQUIRE(::pthread_getcpuclockid(runner.native_handle(), &clock) == 0);
    timespec t{};
    REQUIRE(::clock_gettime(clock, &t) == 0);
    return std::chrono::seconds(t.tv_sec) + std::chrono::nanoseconds(t.tv_nsec);
  }
};

// A socket pair whose one end the loop takes over as connection `id`; the
// other end, the test's, blocks for 5 s at most.
int connect_pair(server::EventLoop& loop, server::ConnectionEntry& entry, int id, std::atomic<int>& active) {
  int pair[2];
  REQUIRE(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, pair) == 0);
  entry.fd = pair[0];
  ::fcntl(pair[1], F_SETFL, ::fcntl(pair[1], F_GETFL) & ~O_NONBLOCK);
  const timeval bound{5, 0};
  ::setsockopt(pair[1], SOL_SOCKET, SO_RCVTIMEO, &bound, sizeof bound);
  ++active;
  loop.adopt(entry, std::make_unique<server::TcpConnection>(
                        pair[0], server::ClientInfo(static_cast<std::uint64_t>(id), server::Transport::tcp, "pair"),
                        std::make_unique<Plain>(pair[0]), 0, 60'000, std::chrono::steady_clock::now()));
  return pair[1];
}

}  // namespace

TEST_CASE("the event loop serves first the connection whose request came first and not the one that connected first") {
  Recorder handler;
  server::RequestWorkers workers(2, "test-worker");
  std::mutex registry;
  std::atomic<int> active{0};
  std::atomic<bool> stop{false};
  server::EventLoop loop({handler, workers, registry, active, stop, "tcp"});
  constexpr int kConnections = 4;
  std::array<server::ConnectionEntry, kConnections> entries;  // outlive the loop's run: it closes them
  std::array<int, kConnections> client_fds{};
  Running running{loop, stop};
  for (int i = 0; i < kConnections; ++i) client_fds[i] = connect_pair(loop, entries[i], i, active);
  // One request each: every connection is now watched by the loop.
  for (int i = 0; i < kConnections; ++i) {
    send_read(client_fds[i], 1);
    take_reply(client_fds[i]);
  }
  REQUIRE(handler.wait_for_requests(kConnections));
  // Connection 0's next request holds the loop; meanwhile 3, 2 and 1 send theirs, in that order.
  send_read(client_fds[0], 2);
  REQUIRE(handler.wait_for_requests(kConnections + 1));
  for (const int i : {3, 2, 1}) send_read(client_fds[i], 2);
  handler.release();
  REQUIRE(handler.wait_for_requests(2 * kConnections));
  const auto order = handler.order();
  CHECK(std::vector<std::uint64_t>(order.begin() + kConnections, order.end()) == std::vector<std::uint64_t>{0, 3, 2, 1});
  for (const int i : {0, 3, 2, 1}) take_reply(client_fds[i]);
  for (const int fd : client_fds) ::close(fd);
}

TEST_CASE("an event loop that polls answers back-to-back requests and sleeps once its client goes quiet") {
  Recorder handler;
  server::RequestWorkers workers(2, "test-worker");
  std::mutex registry;
  std::atomic<int> active{0};
  std::atomic<bool> stop{false};
  // The longest window --poll-us allows: a slow (sanitized) build's client still answers within it.
  server::EventLoop loop({handler, workers, registry, active, stop, "tcp", 1000us});
  server::ConnectionEntry entry;  // outlives the loop's run: it closes it
  Running running{loop, stop};
  const int fd = connect_pair(loop, entry, 7, active);
  // Each request as soon as the last answer is in: the loop learns to poll.
  constexpr int kRequests = 500;
  for (int i = 0; i < kRequests; ++i) {
    send_read(fd, static_cast<std::uint8_t>(i));
    take_reply(fd);
  }
  CHECK(handler.order() == std::vector<std::uint64_t>(kRequests, 7));
  const auto busy = loop.poll_counts();
  CHECK(busy.caught > kRequests / 4);  // many requests found the loop polling, not asleep (a busy CI machine: not all)
  // Quiet: after one more window (the wait that follows the last answer)
  // the loop sleeps: no more polling, and a sleeping thread uses no CPU. A
  // loop that kept polling would use most of the 300 ms.
  std::this_thread::sleep_for(50ms);
  const auto quiet = loop.poll_counts();
  const auto before = running.cpu_time();
  std::this_thread::sleep_for(300ms);
  CHECK(running.cpu_time() - before < 30ms);
  CHECK(loop.poll_counts().polls == quiet.polls);
  // And it still wakes for the next request.
  send_read(fd, 1);
  take_reply(fd);
  ::close(fd);
}
