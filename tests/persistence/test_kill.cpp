// kill -9 in the middle of a storm of writes: no acknowledged write is lost and
// the database stays intact. The writer (storm/storm_writer.cpp) prints an ack
// line only after commit() returned, as the server answers Modbus only then.
// Loops: 20 by default; PERSISTENCE_KILL_LOOPS=500 for a long run.
#include <catch2/catch.hpp>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include "helpers.hpp"
#include "tests/support/process.hpp"

using namespace persistence;

namespace {

std::vector<SettingDefault> storm_defaults() {
  std::vector<SettingDefault> d;
  for (int k = 0; k < 8; ++k) d.push_back({"storm.k" + std::to_string(k), 0});
  d.push_back({"storm.pair.a", 0});
  d.push_back({"storm.pair.b", 0});
  return d;
}

struct RunResult {
  std::string output;
  int status = 0;
};

// Starts the writer, waits until it is ready, lets it write for `run_for`, then SIGKILLs it.
RunResult run_and_kill(const std::string& db, int backup_interval_ms, unsigned seed, std::chrono::milliseconds run_for) {
  test_support::Spawned writer;
  REQUIRE_NOTHROW(writer = test_support::spawn({SETTINGS_STORM_WRITER, db, std::to_string(backup_interval_ms),
                                                std::to_string(seed)},
                                               test_support::Output::pipe(), test_support::Output::inherit()));
  const int out_fd = writer.stdout_fd;
  const pid_t pid = writer.pid;

  std::mutex mu;
  std::string out;
  std::thread reader([&] {
    char buf[4096];
    for (;;) {
      ssize_t n = ::read(out_fd, buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      std::lock_guard lock(mu);
      out.append(buf, static_cast<std::size_t>(n));
    }
  });
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  for (;;) {
    {
      std::lock_guard lock(mu);
      if (out.find('\n') != std::string::npos) break;
    }
    if (std::chrono::steady_clock::now() > deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  std::this_thread::sleep_for(run_for);
  ::kill(pid, SIGKILL);  // by PID: only the writer we started
  RunResult r;
  ::waitpid(pid, &r.status, 0);
  reader.join();
  ::close(out_fd);
  r.output = std::move(out);
  return r;
}

}  // namespace

TEST_CASE("writes acknowledged before the process is killed are all still there and the database is intact",
          "[persistence][kill]") {
  int loops = 20;
  if (const char* env = std::getenv("PERSISTENCE_KILL_LOOPS")) loops = std::max(1, std::atoi(env));
  test::TempDir dir;
  const auto db = dir.file("storm.db");
  std::mt19937 rng(12345);
  std::map<std::string, std::int64_t> acked;  // last acknowledged value per register, over all runs
  std::size_t total_acks = 0;

  for (int loop = 0; loop < loops; ++loop) {
    const int interval = (loop % 2 == 0) ? 0 : 1000;  // even loops: a backup after every commit
    const auto run_for = std::chrono::milliseconds(50 + static_cast<int>(rng() % 251));
    auto run = run_and_kill(db, interval, static_cast<unsigned>(rng()), run_for);
    INFO("loop " << loop << ", ran " << run_for.count() << " ms, backup interval " << interval);
    REQUIRE(WIFSIGNALED(run.status));
    REQUIRE(WTERMSIG(run.status) == SIGKILL);
    REQUIRE(run.output.rfind("ready", 0) == 0);
    CHECK(run.output.rfind("ready restored", 0) != 0);  // a kill never needs a restore

    std::istringstream lines(run.output);
    std::string line;
    while (std::getline(lines, line)) {
      if (lines.eof()) break;  // no newline: not a complete acknowledgement
      if (line.rfind("ack ", 0) != 0) continue;
      ++total_acks;
      std::istringstream fields(line.substr(4));
      std::string kv;
      while (fields >> kv) {
        auto eq = kv.find('=');
        acked[kv.substr(0, eq)] = std::stoll(kv.substr(eq + 1));
      }
    }

    OpenReport report;
    auto o = test::options();
    auto store = test::open_ok(db, report, o, storm_defaults());
    REQUIRE(report.outcome == OpenOutcome::opened);
    REQUIRE(store.check_integrity());
    auto values = store.load();
    for (const auto& [name, v] : acked) {
      INFO(name << " acknowledged " << v << ", stored " << values[name]);
      REQUIRE(values[name] >= v);
    }
    REQUIRE(values["storm.pair.a"] == values["storm.pair.b"]);
  }
  INFO("acknowledged commits over all runs: " << total_acks);
  CHECK(total_acks > static_cast<std::size_t>(loops));
}
