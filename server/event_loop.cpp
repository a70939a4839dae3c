#include "event_loop.hpp"

#include <spdlog/spdlog.h>
#include <sched.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <optional>
#include <stdexcept>

namespace server {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::uint64_t kWakeId = 0;  // epoll data of the loop's eventfd

// Notes when its connection last sent a request (the least recently active
// connection is the one that gives way when the server is full) and hands
// everything on.
class ActivityHandler final : public RequestHandler {
 public:
  ActivityHandler(RequestHandler& inner, std::atomic<std::int64_t>& last_active_ns)
      : inner_(inner), last_active_ns_(last_active_ns) {}
  Reply handle(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client) override {
    last_active_ns_.store(steady_now_ns());
    return inner_.handle(unit, pdu, client);
  }
  std::optional<Reply> handle_now(std::uint8_t unit, std::span<const std::uint8_t> pdu,
                                  const ClientInfo& client) override {
    last_active_ns_.store(steady_now_ns());
    return inner_.handle_now(unit, pdu, client);
  }
  void disconnected(const ClientInfo& client) override { inner_.disconnected(client); }
  bool release_jogs(const ClientInfo& client) override { return inner_.release_jogs(client); }
  void bus_event(Transport transport, BusEvent event) override { inner_.bus_event(transport, event); }

 private:
  RequestHandler& inner_;
  std::atomic<std::int64_t>& last_active_ns_;
};

}  // namespace

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

EventLoop::EventLoop(Shared shared) : shared_(shared), poll_(shared.poll_longest) {
  epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (epoll_fd_ < 0 || wake_fd_ < 0) throw std::runtime_error(std::string("event loop: ") + std::strerror(errno));
  epoll_event e{};
  e.events = EPOLLIN;
  e.data.u64 = kWakeId;
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, wake_fd_, &e);
}

EventLoop::~EventLoop() {
  ::close(wake_fd_);
  ::close(epoll_fd_);
}

void EventLoop::wake() {
  const std::uint64_t one = 1;
  (void)!::write(wake_fd_, &one, sizeof one);
}

void EventLoop::adopt(ConnectionEntry& entry, std::unique_ptr<TcpConnection> connection) {
  ++held_;
  {
    std::lock_guard lock(inbox_mutex_);
    arrivals_.emplace_back(&entry, std::move(connection));
  }
  wake();
}

void EventLoop::take_inbox(std::vector<std::uint64_t>& ready) {
  std::vector<std::pair<ConnectionEntry*, std::unique_ptr<TcpConnection>>> arrivals;
  std::vector<Answer> answers;
  {
    std::lock_guard lock(inbox_mutex_);
    arrivals.swap(arrivals_);
    answers.swap(answers_);
    answer_wake_sent_ = false;
  }
  const auto now = Clock::now();
  for (auto& [entry, connection] : arrivals) {
    const std::uint64_t id = next_id_++;
    slots_.emplace(id, Slot{entry, std::move(connection)});
    ready.push_back(id);
  }
  for (Answer& a : answers) {
    if (a.reply.resolve) {
      const auto resolve = std::move(a.reply.resolve);
      a.reply = resolve();
    }
    const auto it = slots_.find(a.id);
    if (it == slots_.end()) continue;
    it->second.connection->answered(a.reply, now);
    ready.push_back(a.id);
  }
}

void EventLoop::watch(std::uint64_t id, Slot& slot, std::uint32_t events) {
  if (slot.events == events) return;
  epoll_event e{};
  e.events = events;
  e.data.u64 = id;
  const int op = events == 0 ? EPOLL_CTL_DEL : slot.events == 0 ? EPOLL_CTL_ADD : EPOLL_CTL_MOD;
  ::epoll_ctl(epoll_fd_, op, slot.connection->fd(), &e);
  slot.events = events;
}

void EventLoop::send_off(std::uint64_t id, Slot& slot) {
  // Not watched meanwhile: the connection reads nothing until its reply is
  // in, and a hang-up would wake the loop for nothing until then.
  watch(id, slot, 0);
  // A write of the module unit goes to the service's settings writer, and one
  // of the simulator unit to the control loop, which answer it through this
  // loop; any other request that may wait runs on a worker thread of its own.
  const auto& request = slot.connection->request();
  slot.entry->last_active_ns.store(steady_now_ns());
  shared_.workers.begin_elsewhere();
  if (shared_.handler.handle_later(request.unit, request.pdu, slot.connection->client(), [this, id](Reply reply) {
        post_answer(id, std::move(reply));
        // The last use of this loop and of the workers: the listener may go once none is left.
        shared_.workers.end_elsewhere();
      }))
    return;
  shared_.workers.end_elsewhere();
  shared_.workers.run([this, id, request, client = slot.connection->client(),
                       &last_active = slot.entry->last_active_ns] {
    last_active.store(steady_now_ns());
    post_answer(id, shared_.handler.handle(request.unit, request.pdu, client));
  });
}

void EventLoop::post_answer(std::uint64_t id, Reply reply) {
  bool wake_now = false;
  {
    std::lock_guard lock(inbox_mutex_);
    answers_.push_back({id, std::move(reply)});
    wake_now = !answer_wake_sent_;
    answer_wake_sent_ = true;
  }
  // A settings batch answers several connections of this loop at once: one write wakes it for all.
  if (wake_now) wake();
}

void EventLoop::step(std::uint64_t id, Slot& slot, std::vector<std::uint64_t>& again) {
  ActivityHandler handler(shared_.handler, slot.entry->last_active_ns);
  const TcpConnection::Wait w = slot.connection->advance(Clock::now(), handler);
  TcpConnection& c = *slot.connection;
  if (c.opened() && !slot.announced) {
    slot.announced = true;
    const ClientInfo& info = c.client();
    spdlog::info("{}: client {}{}{} connected ({} active)", shared_.name, info.address, info.identity.empty() ? "" : " ",
                 info.identity, shared_.active.load());
  }
  worked_ = worked_ || w == TcpConnection::Wait::read || w == TcpConnection::Wait::write ||
            w == TcpConnection::Wait::again;
  switch (w) {
    case TcpConnection::Wait::read: watch(id, slot, EPOLLIN | EPOLLRDHUP); break;
    case TcpConnection::Wait::write: watch(id, slot, EPOLLOUT); break;
    case TcpConnection::Wait::again:
      watch(id, slot, EPOLLIN | EPOLLRDHUP);
      again.push_back(id);
      break;
    case TcpConnection::Wait::off_loop: send_off(id, slot); break;
    case TcpConnection::Wait::closed: close(id, slot, false); return;
  }
  note_deadline(slot);
}

void EventLoop::note_deadline(const Slot& slot) {
  // A step only moves its connection's deadline; the earliest of all is
  // looked for again once it has passed (expire_due).
  if (const auto d = slot.connection->deadline(); d && (!next_due_ || *d < *next_due_)) next_due_ = *d;
}

void EventLoop::expire_due(Clock::time_point now, std::vector<std::uint64_t>& ready) {
  if (!next_due_ || now < *next_due_) return;
  next_due_.reset();
  for (const auto& [id, slot] : slots_) {
    const auto d = slot.connection->deadline();
    if (!d) continue;
    if (now >= *d)
      ready.push_back(id);
    else if (!next_due_ || *d < *next_due_)
      next_due_ = *d;
  }
}

void EventLoop::close(std::uint64_t id, Slot& slot, bool stopping) {
  watch(id, slot, 0);
  TcpConnection& c = *slot.connection;
  ConnectionEntry& entry = *slot.entry;
  const bool served = c.opened();
  c.say_goodbye();  // a TLS channel sends close_notify
  std::string closed_for;
  {
    std::lock_guard lock(shared_.registry_mutex);
    closed_for = entry.closed_for;
  }
  const std::string& address = c.client().address;
  if (c.refused()) {
    const std::string reason = stopping ? "server stopping" : c.end_reason();
    if (shared_.refused) shared_.refused(address, reason);
    else spdlog::warn("{}: refused {}: {}", shared_.name, address, reason);
  } else if (!closed_for.empty()) {
    spdlog::info("{}: client {} disconnected: closed to make room for {}", shared_.name, address, closed_for);
  } else {
    spdlog::info("{}: client {} disconnected: {}", shared_.name, address, stopping ? "server stopping" : c.end_reason());
  }
  if (served) shared_.handler.disconnected(c.client());  // its jogs stop, its edit session ends
  {
    // Under the lock: the acceptor never shuts down a descriptor number
    // that another connection may reuse.
    std::lock_guard lock(shared_.registry_mutex);
    ::shutdown(entry.fd, SHUT_RDWR);
    ::close(entry.fd);
    entry.fd = -1;
  }
  --shared_.active;
  --held_;
  entry.finished = true;
  slots_.erase(id);
}

int EventLoop::wait_ms(bool again) const {
  if (again) return 0;
  if (!next_due_) return -1;  // nothing due: a socket, an arrival, an answer or stop() wakes the loop
  const auto ms = std::chrono::ceil<std::chrono::milliseconds>(*next_due_ - Clock::now()).count();
  return static_cast<int>(std::max<std::int64_t>(0, ms));
}

int EventLoop::wait_for_events(std::span<epoll_event> events, bool again) {
  const int size = static_cast<int>(events.size());
  if (again || !worked_) return ::epoll_wait(epoll_fd_, events.data(), size, wait_ms(again));
  const auto began = Clock::now();
  int n = 0;
  if (const auto window = poll_.window(); window.count() > 0) {
    polls_.fetch_add(1, std::memory_order_relaxed);
    const auto until = began + window;
    // Yielding between polls lets another thread of normal priority waiting
    // for this core run (a client on the same computer, the other loop, a
    // worker, the settings writer); the control loop preempts anyway.
    do {
      n = ::epoll_wait(epoll_fd_, events.data(), size, 0);
      if (n == 0) ::sched_yield();
    } while (n == 0 && Clock::now() < until);
    if (n < 0) return n;  // errno as epoll_wait left it
  }
  const bool caught = n > 0;
  if (caught) polls_caught_.fetch_add(1, std::memory_order_relaxed);
  else n = ::epoll_wait(epoll_fd_, events.data(), size, wait_ms(false));
  poll_.waited(Clock::now() - began, caught);
  return n;
}

void EventLoop::run() {
  std::array<epoll_event, 64> events{};
  std::vector<std::uint64_t> ready, again;
  while (!shared_.stop) {
    const int n = wait_for_events(events, !again.empty());
    if (n < 0 && errno != EINTR) {
      spdlog::error("{}: event loop: epoll_wait: {}", shared_.name, std::strerror(errno));
      break;
    }
    for (int i = 0; i < n; ++i) {
      if (events[i].data.u64 == kWakeId) {
        std::uint64_t count = 0;
        (void)!::read(wake_fd_, &count, sizeof count);
        continue;
      }
      ready.push_back(events[i].data.u64);
    }
    take_inbox(ready);
    expire_due(Clock::now(), ready);
    // In the order they became ready (epoll's), the connections that had a
    // turn already last: the one that waited longest is served first.
    ready.insert(ready.end(), again.begin(), again.end());
    again.clear();
    ++turn_;
    worked_ = false;
    for (const std::uint64_t id : ready) {
      const auto it = slots_.find(id);
      if (it == slots_.end() || it->second.turn == turn_) continue;  // gone, or listed twice
      it->second.turn = turn_;
      if (it->second.connection->off_loop()) continue;  // its answer steps it
      step(id, it->second, again);
    }
    ready.clear();
  }
  // Stopping: what arrived meanwhile is closed with the rest.
  std::vector<std::uint64_t> ignored;
  take_inbox(ignored);
  while (!slots_.empty()) close(slots_.begin()->first, slots_.begin()->second, true);
}

}  // namespace server
