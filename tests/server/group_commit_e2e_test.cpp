// Settings written by several clients at once are committed together (group
// commit), and each is answered only once the commit that holds it is
// durable: killed with SIGKILL in the middle, homingd loses no acknowledged
// write (docs/operating.md "Settings: durable, audited, recoverable").
#include <catch2/catch.hpp>

#include <atomic>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "daemon.hpp"

using namespace e2e;

TEST_CASE("eight clients writing settings at once lose no acknowledged write when homingd is killed mid-stream") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  // One setting per client, each written with a rising value.
  const std::vector<std::string> regs{"axis.x.home_position", "axis.y.home_position", "axis.z.home_position",
                                      "axis.a.home_position", "axis.b.home_position", "axis.c.home_position",
                                      "axis.x.pull_off",      "axis.y.pull_off"};
  std::vector<std::atomic<std::int64_t>> acked(regs.size());
  std::vector<std::atomic<std::int64_t>> sent(regs.size());
  std::atomic<std::uint64_t> total{0};
  {
    Daemon d({.db = db});
    std::atomic<bool> stop{false};
    std::vector<std::thread> writers;
    for (std::size_t i = 0; i < regs.size(); ++i) {
      writers.emplace_back([&, i] {
        Client c = Client::tcp(d.port());
        const auto until = Clock::now() + 20s;
        // Bounded: at most 5000 writes or 20 s, or until the daemon is gone.
        for (std::int64_t k = 1001; k <= 6000 && !stop && Clock::now() < until; ++k) {
          sent[i] = k;
          if (c.write(regs[i], k) != 0) return;
          acked[i] = k;
          ++total;
        }
      });
    }
    // Kill it once the writes are well under way (or after 10 s at the latest).
    const auto deadline = Clock::now() + 10s;
    while (total < 400 && Clock::now() < deadline) std::this_thread::sleep_for(10ms);
    REQUIRE(total >= 400);
    d.stop(SIGKILL);
    stop = true;
    for (std::thread& t : writers) t.join();
  }
  Daemon again({.db = db});
  Client c = Client::tcp(again.port());
  for (std::size_t i = 0; i < regs.size(); ++i) {
    INFO(regs[i] << ": acknowledged " << acked[i] << ", last sent " << sent[i]);
    const std::int64_t stored = c.read(regs[i]);
    // Every acknowledged value is there; the write in flight may or may not be.
    CHECK(stored >= acked[i].load());
    CHECK(stored <= sent[i].load());
  }
}

namespace {

// The names homingd gave its threads (/proc/PID/task/TID/comm).
std::multiset<std::string> thread_names(pid_t pid) {
  std::multiset<std::string> names;
  for (const auto& task : std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string name;
    std::getline(comm, name);
    names.insert(name);
  }
  return names;
}

}  // namespace

TEST_CASE("settings written by eight TCP clients at once are committed by the one settings writer, with no thread "
          "started per write") {
  Daemon d;
  std::vector<std::thread> writers;
  std::atomic<int> failed{0};
  std::atomic<int> acked{0};
  const std::vector<std::string> regs{"axis.x.home_position", "axis.y.home_position", "axis.z.home_position",
                                      "axis.a.home_position", "axis.b.home_position", "axis.c.home_position",
                                      "axis.x.pull_off",      "axis.y.pull_off"};
  for (std::size_t i = 0; i < regs.size(); ++i)
    writers.emplace_back([&, i] {
      Client c = Client::tcp(d.port());
      for (std::int64_t k = 1001; k <= 1100; ++k) {  // bounded: 100 writes each
        if (c.write(regs[i], k) != 0) {
          ++failed;
          return;
        }
        ++acked;
      }
    });
  for (std::thread& t : writers) t.join();
  CHECK(failed == 0);
  CHECK(acked == 800);
  const auto names = thread_names(d.pid());
  CAPTURE(std::vector<std::string>(names.begin(), names.end()));
  CHECK(names.count("settings-write") == 1);
  CHECK(names.count("tcp-write") == 0);  // RequestWorkers: only a write that waits for the control loop starts one
  Client c = Client::tcp(d.port());
  for (const std::string& r : regs) CHECK(c.read(r) == 1100);
}
