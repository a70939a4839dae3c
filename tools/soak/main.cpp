// homing_soak: drives a running homingd with many Modbus/TCP clients at once
// for a bounded time and checks invariants as it goes:
//   - every answered settings write reads back; exception 06 during a homing
//     cycle is expected (counted), any other exception is a violation;
//   - reads never fail, the daemon always answers;
//   - status.heartbeat advances;
//   - every homing cycle ends with a result (homed, aborted, the injected fault);
//   - after a homing with noise 0, each axis position == home_position and the
//     simulator's carriage rests at sensor_max + hysteresis + pull_off.
// Roles (roles.hpp): client 0 runs home/abort cycles, client 1 injects
// simulator faults (the two take turns on the machine), the others poll status
// or write settings and read them back. Prints a summary (report.hpp); exit 1
// on any violation. With --spawn it starts homingd itself (tests/support).
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "counted_client.hpp"
#include "machine.hpp"
#include "report.hpp"
#include "roles.hpp"
#include "tests/support/homingd.hpp"

using namespace soak;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

namespace {

struct Options {
  std::string tcp = "127.0.0.1:1502", spawn_path;
  int clients = 8, unit = 1, sim_unit = 247;
  double duration_s = 20, time_scale = 10;
  std::uint64_t seed = 1;
  pid_t pid = 0;
};

// The options, or the exit code of a parse that ends the program (help, usage).
std::variant<Options, int> parse_options(int argc, char** argv) {
  CLI::App app{"homing_soak: many Modbus clients against a running homingd for a bounded time, checking invariants.\n"
               "Exit 0 when no invariant was violated, 1 otherwise, 2 usage, 3 cannot reach the daemon."};
  Options o;
  app.add_option("--tcp", o.tcp, "homingd address HOST:PORT")->capture_default_str();
  app.add_option("--clients", o.clients, "Modbus clients at once (at least 4)")->check(CLI::Range(4, 200))->capture_default_str();
  app.add_option("--duration-s", o.duration_s, "how long to run")->check(CLI::Range(1.0, 7.0 * 24 * 3600))->capture_default_str();
  app.add_option("--seed", o.seed, "random seed")->capture_default_str();
  app.add_option("--unit", o.unit, "module unit id")->capture_default_str();
  app.add_option("--sim-unit", o.sim_unit, "simulator unit id")->capture_default_str();
  app.add_option("--pid", o.pid, "homingd's PID, for its memory (VmRSS) at start and end");
  app.add_option("--spawn", o.spawn_path, "start this homingd (temporary database, free port) instead of --tcp");
  app.add_option("--time-scale", o.time_scale, "--time-scale of the spawned homingd")->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }
  return o;
}

// Exact simulated edges (noise 0), seeks bounded for the stuck sensor, no alarm.
void set_up_machine(CountedClient& c) {
  for (auto a : kHomed) {
    c.must_write(sim(a, "noise"), 0);
    c.must_write(sim(a, "fault"), 0);
    c.must_write(ax(a, "max_seek_travel"), 300000);
  }
  (void)command(c, "cmd.abort");
  std::this_thread::sleep_for(50ms);
  (void)command(c, "cmd.reset_alarm");
}

// Registers the writers own (one owner each, so a read-back is exact): jog
// feedrates of the homing axes, settings of the disabled axes A B C.
std::vector<std::vector<Owned>> writer_registers(int writers) {
  std::vector<Owned> pool;
  for (auto a : kHomed) pool.push_back({ax(a, "jog_feedrate"), 500, 3000});
  for (std::string_view a : {"a", "b", "c"}) {
    pool.push_back({ax(a, "pull_off"), 0, 5000});
    pool.push_back({ax(a, "home_position"), -10000, 10000});
    pool.push_back({ax(a, "seek_feedrate"), 200, 2000});
    pool.push_back({ax(a, "final_position"), -50000, 50000});
  }
  std::vector<std::vector<Owned>> owned(static_cast<std::size_t>(writers));
  for (std::size_t i = 0; i < pool.size(); ++i) owned[i % owned.size()].push_back(pool[i]);
  return owned;
}

// Every client in its role for the duration; the seconds it took.
double run_roles(std::vector<std::unique_ptr<CountedClient>>& cs, Shared& shared, const Options& o) {
  const int writers = std::max(1, (o.clients - 2) / 2);
  auto owned = writer_registers(writers);
  const auto t0 = Clock::now();
  std::vector<std::thread> threads;
  threads.emplace_back(cycle_role, std::ref(*cs[0]), std::ref(shared), o.seed * 7919 + 1);
  threads.emplace_back(fault_role, std::ref(*cs[1]), std::ref(shared), o.seed * 7919 + 2);
  for (int i = 2; i < o.clients; ++i) {
    const int k = i - 2;
    auto& c = *cs[static_cast<std::size_t>(i)];
    const std::uint64_t seed = o.seed * 7919 + static_cast<std::uint64_t>(i);
    if (k < writers)
      threads.emplace_back(writer_role, std::ref(c), std::ref(shared), owned[static_cast<std::size_t>(k)], seed);
    else
      threads.emplace_back(poller_role, std::ref(c), std::ref(shared), seed);
  }
  while (Clock::now() - t0 < std::chrono::duration<double>(o.duration_s)) std::this_thread::sleep_for(100ms);
  shared.stop = true;
  for (auto& t : threads) t.join();
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// SIGTERM must end the spawned homingd cleanly within 20 s (a sanitized one
// runs its leak check on the way out), with no sanitizer report in its stderr.
std::optional<int> stop_daemon(test_support::Homingd& daemon, Shared& shared) {
  const auto status = daemon.stop(SIGTERM, test_support::kStopTimeout);
  if (!status)
    shared.violation("homingd did not exit within 20 s of SIGTERM");
  else if (!WIFEXITED(*status) || WEXITSTATUS(*status) != 0)
    shared.violation(fmt::format("homingd ended with status {} after SIGTERM (see {})", *status, daemon.log_path()));
  const auto reports = test_support::sanitizer_reports(daemon.log());
  for (const auto& line : reports) shared.violation("sanitizer report in homingd's stderr: " + line);
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  const auto parsed = parse_options(argc, argv);
  if (const int* exit_code = std::get_if<int>(&parsed)) return *exit_code;
  const Options& o = std::get<Options>(parsed);

  std::optional<test_support::Homingd> daemon;
  std::string host = "127.0.0.1";
  int port = 1502;
  pid_t pid = o.pid;
  try {
    if (!o.spawn_path.empty()) {
      test_support::DaemonOptions options;
      options.program = o.spawn_path;
      options.time_scale = o.time_scale;
      options.extra = {"--log-level", "warn"};
      options.temp_prefix = "homing-soak";
      daemon.emplace(std::move(options));
      port = daemon->port();
      pid = daemon->pid();
    } else {
      const auto colon = o.tcp.rfind(':');
      host = o.tcp.substr(0, colon);
      port = colon == std::string::npos ? 502 : std::stoi(o.tcp.substr(colon + 1));
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "homing_soak: {}\n", e.what());
    return 3;
  }
  RunFacts run;
  run.clients = o.clients;
  run.seed = o.seed;
  run.rss_start_kb = pid > 0 ? vm_rss_kb(pid) : std::nullopt;

  Shared shared;
  std::vector<std::unique_ptr<CountedClient>> cs;
  try {
    for (int i = 0; i < o.clients; ++i)
      cs.push_back(std::make_unique<CountedClient>(host, port, i, shared, o.unit, o.sim_unit));
  } catch (const std::exception& e) {
    fmt::print(stderr, "homing_soak: {}\n", e.what());
    if (daemon) daemon->keep_files();  // its log says why it did not answer
    return 3;
  }

  set_up_machine(*cs[0]);
  run.elapsed_s = run_roles(cs, shared, o);
  run.rss_end_kb = pid > 0 ? vm_rss_kb(pid) : std::nullopt;

  Stats total;
  for (auto& c : cs) total.merge(c->stats);
  cs.clear();

  if (daemon) run.exit_status = stop_daemon(*daemon, shared);
  print_summary(run, total, shared);
  if (daemon && shared.violation_count > 0) daemon->keep_files();
  return shared.violation_count == 0 ? 0 : 1;
}
