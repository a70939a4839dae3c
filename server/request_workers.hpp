#pragma once
// The threads that run the requests that may wait (server/tcp_connection.hpp,
// may_wait: writes wait for their durable commit or for the control loop),
// so that no event loop ever waits for one. A thread per request in flight,
// up to the connections the server admits (each has at most one in flight),
// so a write never queues behind another and writes that arrive together
// still meet in one group commit; threads stay for the next ones.
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace server {

class RequestWorkers {
 public:
  // name: the threads' name ("tcp-write").
  RequestWorkers(std::size_t max_threads, std::string name)
      : max_threads_(max_threads < 1 ? 1 : max_threads), name_(std::move(name)) {}
  ~RequestWorkers() { join(); }
  RequestWorkers(const RequestWorkers&) = delete;
  RequestWorkers& operator=(const RequestWorkers&) = delete;

  void run(std::function<void()> job);
  // A request answered on a thread of another (RequestHandler::handle_later,
  // the settings writer): counted from before it is handed over until its
  // answer is posted to its loop, so that join() waits for it as well.
  void begin_elsewhere();
  void end_elsewhere();
  // Runs what is queued, waits for the requests answered elsewhere, then
  // ends the threads.
  void join();
  std::size_t threads() const;

 private:
  void work();

  const std::size_t max_threads_;
  const std::string name_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> jobs_;
  std::vector<std::thread> threads_;
  std::size_t idle_ = 0;
  std::mutex elsewhere_mutex_;  // the count below and its condition only
  std::size_t elsewhere_ = 0;
  std::condition_variable elsewhere_done_;
  bool stopping_ = false;
};

}  // namespace server
