#include "request_workers.hpp"

#include "thread_name.hpp"

namespace server {

void RequestWorkers::run(std::function<void()> job) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;  // the server stops: its connections close unanswered
    jobs_.push_back(std::move(job));
    if (jobs_.size() > idle_ && threads_.size() < max_threads_) threads_.emplace_back([this] {
        name_this_thread(name_);
        work();
      });
  }
  // After the unlock: a thread woken under the lock would at once wait for it
  // again (two more context switches on the write's path).
  wake_.notify_one();
}

void RequestWorkers::work() {
  std::unique_lock lock(mutex_);
  for (;;) {
    ++idle_;
    wake_.wait(lock, [this] { return stopping_ || !jobs_.empty(); });
    --idle_;
    if (jobs_.empty()) return;  // stopping, nothing left
    auto job = std::move(jobs_.front());
    jobs_.pop_front();
    lock.unlock();
    job();
    lock.lock();
  }
}

// No lock on the way: end_elsewhere may run on the control loop's thread (a
// simulator write's answer), which must not wait for a thread that holds the
// mutex while it starts a worker. Only join() waits, and only it is woken.
void RequestWorkers::begin_elsewhere() { elsewhere_.fetch_add(1); }

void RequestWorkers::end_elsewhere() {
  if (elsewhere_.fetch_sub(1) == 1 && joining_.load()) {
    std::lock_guard lock(mutex_);
    elsewhere_done_.notify_all();
  }
}

void RequestWorkers::join() {
  std::vector<std::thread> threads;
  {
    std::unique_lock lock(mutex_);
    stopping_ = true;
    threads.swap(threads_);
    joining_.store(true);  // before the count is read: an answer ending after this wakes the wait
    elsewhere_done_.wait(lock, [this] { return elsewhere_.load() == 0; });
  }
  wake_.notify_all();
  for (std::thread& t : threads) t.join();
}

std::size_t RequestWorkers::threads() const {
  std::lock_guard lock(mutex_);
  return threads_.size();
}

}  // namespace server
