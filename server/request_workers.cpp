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

// A mutex of its own, held only for the count: end_elsewhere may run on the
// control loop's thread (a simulator write's answer), which must not wait
// for run() starting a worker under mutex_. Counted and woken under it, so
// join() cannot return while an answering thread still touches this object.
void RequestWorkers::begin_elsewhere() {
  std::lock_guard lock(elsewhere_mutex_);
  ++elsewhere_;
}

void RequestWorkers::end_elsewhere() {
  std::lock_guard lock(elsewhere_mutex_);
  if (--elsewhere_ == 0) elsewhere_done_.notify_all();
}

void RequestWorkers::join() {
  std::vector<std::thread> threads;
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    threads.swap(threads_);
  }
  {
    std::unique_lock lock(elsewhere_mutex_);
    elsewhere_done_.wait(lock, [this] { return elsewhere_ == 0; });
  }
  wake_.notify_all();
  for (std::thread& t : threads) t.join();
}

std::size_t RequestWorkers::threads() const {
  std::lock_guard lock(mutex_);
  return threads_.size();
}

}  // namespace server
