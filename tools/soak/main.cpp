// homing_soak: drives a running homingd with many Modbus/TCP clients at once
// for a bounded time and checks invariants as it goes:
//   - every answered settings write reads back; exception 06 during a homing
//     cycle is expected (counted), any other exception is a violation;
//   - reads never fail, the daemon always answers;
//   - status.heartbeat advances;
//   - every homing cycle ends with a result (homed, aborted, the injected fault);
//   - after a homing with noise 0, each axis position == home_position and the
//     simulator's carriage rests at sensor_max + hysteresis + pull_off.
// Roles: client 0 runs home/abort cycles, client 1 injects simulator faults
// (the two take turns on the machine), the others poll status or write
// settings and read them back. Prints a summary; exit 1 on any violation.
#include <CLI/CLI.hpp>
#include <fcntl.h>
#include <fmt/format.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <arpa/inet.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "homing/alarms.hpp"
#include "homing/status.hpp"
#include "registers/codec.hpp"
#include "registers/lookup.hpp"

extern char** environ;

namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;
using registers::Register;
using registers::Table;

// ------------------------------------------------------------------ results
struct Shared {
  std::mutex mu;
  std::vector<std::string> violations;
  std::uint64_t violation_count = 0;
  void violation(std::string what) {
    std::lock_guard lock(mu);
    ++violation_count;
    if (violations.size() < 40) violations.push_back(std::move(what));
  }
  std::mutex machine;  // the cycle and fault clients take turns
  std::string last_event;  // what the machine did last (under `machine`), for messages
  std::atomic<bool> stop{false};
};

struct Stats {
  std::uint64_t requests = 0;
  std::map<std::string, std::uint64_t> errors;  // by kind
  std::uint64_t expected_busy = 0;              // exception 06 on writes during homing
  std::vector<float> latency_ms;
  std::uint64_t writes_verified = 0, polls = 0;
  std::uint64_t cycles_completed = 0, cycles_aborted = 0, faults_injected = 0;
  void merge(const Stats& o) {
    requests += o.requests;
    for (const auto& [k, v] : o.errors) errors[k] += v;
    expected_busy += o.expected_busy;
    latency_ms.insert(latency_ms.end(), o.latency_ms.begin(), o.latency_ms.end());
    writes_verified += o.writes_verified;
    polls += o.polls;
    cycles_completed += o.cycles_completed;
    cycles_aborted += o.cycles_aborted;
    faults_injected += o.faults_injected;
  }
};

int exception_of(int err) { return err > MODBUS_ENOBASE && err <= EMBXGTAR ? err - MODBUS_ENOBASE : 0; }

const Register& reg(const std::string& name) {
  const Register* r = registers::find_register(name);
  if (!r) throw std::runtime_error("no register " + name);
  return *r;
}
std::string ax(std::string_view a, std::string_view f) { return fmt::format("axis.{}.{}", a, f); }
std::string sim(std::string_view a, std::string_view f) { return fmt::format("sim.{}.{}", a, f); }

// ------------------------------------------------------------------ client
class Client {
 public:
  Client(const std::string& host, int port, int id, Shared& shared, int unit, int sim_unit)
      : id_(id), shared_(shared), unit_(unit), sim_unit_(sim_unit) {
    ctx_ = modbus_new_tcp(host.c_str(), port);
    if (!ctx_) throw std::runtime_error("modbus_new_tcp failed");
    modbus_set_response_timeout(ctx_, 2, 0);
    if (modbus_connect(ctx_) != 0) {
      const int e = errno;
      modbus_free(ctx_);
      throw std::runtime_error(fmt::format("cannot connect to {}:{}: {}", host, port, modbus_strerror(e)));
    }
  }
  ~Client() {
    modbus_close(ctx_);
    modbus_free(ctx_);
  }
  Stats stats;

  // Raw value, or nullopt (counted, and a violation: reads must always work).
  std::optional<std::int64_t> read(const std::string& name) {
    const Register& r = reg(name);
    select(r);
    std::uint16_t w[2] = {0, 0};
    std::uint8_t bit = 0;
    int rc = timed([&] {
      switch (r.table) {
        case Table::coil: return modbus_read_bits(ctx_, r.address, 1, &bit);
        case Table::discrete_input: return modbus_read_input_bits(ctx_, r.address, 1, &bit);
        case Table::holding_register: return modbus_read_registers(ctx_, r.address, r.words(), w);
        case Table::input_register: return modbus_read_input_registers(ctx_, r.address, r.words(), w);
      }
      return -1;
    });
    if (rc < 0) {
      shared_.violation(fmt::format("client {}: reading {} failed: {}", id_, name, last_error_));
      return std::nullopt;
    }
    if (r.table == Table::coil || r.table == Table::discrete_input) return bit;
    return registers::decode_words(r, std::span<const std::uint16_t>(w, r.words()), registers::WordOrder::high_first);
  }
  // Block read of input registers (status polls).
  bool read_inputs(int start, int count, std::uint16_t* out) {
    modbus_set_slave(ctx_, unit_);
    if (timed([&] { return modbus_read_input_registers(ctx_, start, count, out); }) < 0) {
      shared_.violation(fmt::format("client {}: reading input registers {}..{} failed: {}", id_, start, start + count - 1,
                                    last_error_));
      return false;
    }
    return true;
  }
  // 0, the exception code, or -1 for no answer (counted by kind).
  int write(const std::string& name, std::int64_t raw) {
    const Register& r = reg(name);
    select(r);
    int rc;
    if (r.table == Table::coil) {
      rc = timed([&] { return modbus_write_bit(ctx_, r.address, raw ? 1 : 0); });
    } else {
      std::uint16_t w[2] = {0, 0};
      registers::encode_words(r, raw, registers::WordOrder::high_first, std::span<std::uint16_t>(w, r.words()));
      rc = timed([&] { return modbus_write_registers(ctx_, r.address, r.words(), w); });
    }
    if (rc >= 0) return 0;
    return last_exception_ ? last_exception_ : -1;
  }
  // A write that must be accepted (set-up and machine steps).
  bool must_write(const std::string& name, std::int64_t raw) {
    const int rc = write(name, raw);
    if (rc != 0) shared_.violation(fmt::format("client {}: writing {} = {} failed: {}", id_, name, raw, last_error_));
    return rc == 0;
  }
  // Counts an error kind that the caller decided was expected, not an error.
  void expected_exception() {
    if (auto it = stats.errors.find(last_error_); it != stats.errors.end() && --it->second == 0) stats.errors.erase(it);
    ++stats.expected_busy;
  }
  const std::string& last_error() const { return last_error_; }

 private:
  template <class F>
  int timed(F f) {
    const auto t0 = Clock::now();
    const int rc = f();
    const int err = errno;
    stats.latency_ms.push_back(std::chrono::duration<float, std::milli>(Clock::now() - t0).count());
    ++stats.requests;
    last_exception_ = 0;
    if (rc < 0) {
      last_exception_ = exception_of(err);
      last_error_ = last_exception_ ? fmt::format("exception {:02X}", last_exception_)
                                    : (err == ETIMEDOUT ? std::string("timeout") : std::string(modbus_strerror(err)));
      ++stats.errors[last_error_];
      if (!last_exception_) modbus_flush(ctx_);
    }
    return rc;
  }
  void select(const Register& r) {
    modbus_set_slave(ctx_, r.unit == registers::Unit::simulator ? sim_unit_ : unit_);
  }

  modbus_t* ctx_ = nullptr;
  int id_;
  Shared& shared_;
  int unit_, sim_unit_;
  int last_exception_ = 0;
  std::string last_error_;
};

constexpr std::array<std::string_view, 3> kHomed = {"x", "y", "z"};

// Waits until the control loop published three new snapshots, so it took a
// command just written (its mailbox is taken with try_lock; with --time-scale
// the heartbeat counts several engine steps per period).
void let_loop_take(Client& c, std::int64_t h0) {
  const auto deadline = Clock::now() + 2s;
  std::int64_t last = h0;
  int changes = 0;
  while (Clock::now() < deadline && changes < 3) {
    auto h = c.read("status.heartbeat");
    if (!h) return;
    if (*h != last) {
      ++changes;
      last = *h;
    }
    if (changes < 3) std::this_thread::sleep_for(1ms);
  }
}

// Writes a command coil; the command result once the loop took it.
std::optional<int> command(Client& c, const std::string& coil) {
  const auto h0 = c.read("status.heartbeat");
  if (!h0 || !c.must_write(coil, 1)) return std::nullopt;
  let_loop_take(c, *h0);
  auto r = c.read("status.last_command_result");
  return r ? std::optional<int>(static_cast<int>(*r)) : std::nullopt;
}

// Waits for the end of a homing cycle; false (and a violation) if it does not end.
bool wait_cycle_end(Client& c, Shared& shared, std::chrono::seconds timeout, const std::string& what) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    auto homing = c.read("status.homing");
    auto state = c.read("status.state");
    if (homing && state && *homing == 0 && *state != static_cast<int>(homing::MachineState::homing)) {
      bool busy = false;
      for (auto a : kHomed)
        if (auto b = c.read(ax(a, "busy")); b && *b) busy = true;
      if (!busy) return true;
    }
    std::this_thread::sleep_for(5ms);
  }
  shared.violation(fmt::format("{}: the homing cycle did not end with a result within {} s", what, timeout.count()));
  return false;
}

std::map<std::string, int> axis_alarms(Client& c) {
  std::map<std::string, int> out;
  for (auto a : kHomed)
    if (auto v = c.read(ax(a, "alarm")); v && *v) out[std::string(a)] = static_cast<int>(*v);
  return out;
}

std::string alarms_text(const std::map<std::string, int>& m) {
  std::string s;
  for (const auto& [a, code] : m)
    s += fmt::format("{}{}: {}", s.empty() ? "" : ", ", a, homing::alarm_name(static_cast<homing::AlarmCode>(code)));
  return s.empty() ? "none" : s;
}

bool reset_and_check(Client& c, Shared& shared, const std::string& what) {
  auto r = command(c, "cmd.reset_alarm");
  if (!r) return false;
  auto state = c.read("status.state");
  if (!state || *state == static_cast<int>(homing::MachineState::alarm)) {
    shared.violation(fmt::format("{}: reset did not clear the alarm (result {}, alarms {})", what,
                                 homing::command_result_name(static_cast<homing::CommandResult>(*r)),
                                 alarms_text(axis_alarms(c))));
    return false;
  }
  return true;
}

// Positions after a successful homing against the simulator's truth (noise 0).
void check_truth(Client& c, Shared& shared, const std::map<std::string, std::int64_t>& pull_off,
                 const std::map<std::string, std::int64_t>& home) {
  for (auto a : kHomed) {
    const std::string s(a);
    auto pos = c.read(ax(a, "position"));
    auto homed = c.read(ax(a, "homed"));
    auto actual = c.read(sim(a, "actual_position"));
    auto smax = c.read(sim(a, "sensor_max"));
    auto hyst = c.read(sim(a, "hysteresis"));
    if (!pos || !homed || !actual || !smax || !hyst) continue;
    if (*homed != 1) shared.violation(fmt::format("after homing {} is not homed", s));
    if (std::llabs(*pos - home.at(s)) > 1)
      shared.violation(fmt::format("after homing {} position {:.3f} mm != home_position {:.3f} mm", s, *pos / 1000.0,
                                   home.at(s) / 1000.0));
    const std::int64_t expected = *smax + *hyst + pull_off.at(s);
    if (std::llabs(*actual - expected) > 20) {
      const auto trig = c.read(ax(a, "trigger_position")), corr = c.read(ax(a, "home_correction"));
      shared.violation(fmt::format("after homing {}: simulator carriage at {:.3f} mm, expected {:.3f} mm "
                                   "(sensor_max + hysteresis + pull_off); trigger_position {:.3f}, home_correction "
                                   "{:.3f}; before this cycle: {}",
                                   s, *actual / 1000.0, expected / 1000.0, trig.value_or(0) / 1000.0,
                                   corr.value_or(0) / 1000.0, shared.last_event));
    }
  }
}

// ------------------------------------------------------------------ roles
void cycle_role(Client& c, Shared& shared, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto uni = [&](std::int64_t lo, std::int64_t hi) { return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng); };
  while (!shared.stop) {
    {
      std::lock_guard machine(shared.machine);
      std::map<std::string, std::int64_t> pull_off, home;
      bool ok = true;
      for (auto a : kHomed) {
        const std::string s(a);
        pull_off[s] = uni(500, 3000);
        home[s] = uni(-20000, 20000);
        ok = ok && c.must_write(ax(a, "pull_off"), pull_off[s]) && c.must_write(ax(a, "home_position"), home[s]);
        ok = ok && c.must_write(sim(a, "actual_position"), uni(5000, 120000));
        if (auto v = c.read(ax(a, "pull_off")); v && *v != pull_off[s])
          shared.violation(fmt::format("{} read back {} after writing {}", ax(a, "pull_off"), *v, pull_off[s]));
      }
      // Let the loop apply the placements before the command: in the period
      // that takes both, the engine would still see the sensor as it was
      // before the carriage was placed (see README, Operator tools).
      if (auto h = c.read("status.heartbeat")) let_loop_take(c, *h);
      if (ok) {
        const bool do_abort = uni(0, 9) < 3;
        auto r = command(c, "cmd.home_all");
        if (r && *r != static_cast<int>(homing::CommandResult::accepted)) {
          shared.violation(fmt::format("home all not accepted: {} (alarms {})",
                                       homing::command_result_name(static_cast<homing::CommandResult>(*r)),
                                       alarms_text(axis_alarms(c))));
          reset_and_check(c, shared, "after a refused home");
        } else if (r) {
          if (do_abort) {
            std::this_thread::sleep_for(std::chrono::milliseconds(uni(20, 400)));
            (void)command(c, "cmd.abort");
          }
          if (wait_cycle_end(c, shared, 120s, do_abort ? "abort" : "home all")) {
            const auto state = c.read("status.state");
            const auto alarms = axis_alarms(c);
            if (state && *state == static_cast<int>(homing::MachineState::homed) && alarms.empty()) {
              check_truth(c, shared, pull_off, home);
              ++c.stats.cycles_completed;
              shared.last_event = do_abort ? "abort came after the end of a completed cycle" : "completed cycle";
            } else if (do_abort) {
              bool only_aborted = !alarms.empty();
              for (const auto& [a, code] : alarms)
                if (code != static_cast<int>(homing::AlarmCode::aborted)) only_aborted = false;
              if (!only_aborted) shared.violation(fmt::format("abort ended with alarms {}", alarms_text(alarms)));
              ++c.stats.cycles_aborted;
              reset_and_check(c, shared, "after abort");
              shared.last_event = "aborted cycle, reset";
            } else {
              shared.violation(fmt::format("home all ended {} with alarms {}",
                                           state ? homing::state_name(static_cast<homing::MachineState>(*state)) : "?",
                                           alarms_text(alarms)));
              reset_and_check(c, shared, "after a failed home");
            }
          }
        }
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(uni(5, 50)));
  }
}

void fault_role(Client& c, Shared& shared, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto uni = [&](std::int64_t lo, std::int64_t hi) { return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng); };
  while (!shared.stop) {
    // Let the cycle client run a few cycles in between.
    for (int i = 0; i < 30 && !shared.stop; ++i) std::this_thread::sleep_for(100ms);
    if (shared.stop) break;
    std::lock_guard machine(shared.machine);
    const std::string a(kHomed[static_cast<std::size_t>(uni(0, 2))]);
    if (uni(0, 1) == 0) {
      // Sensor stuck inactive: the seek must end with sensor_not_found on that axis.
      if (!c.must_write(sim(a, "fault"), 2)) continue;
      ++c.stats.faults_injected;
      auto r = command(c, "cmd.home." + a);
      if (r && *r == static_cast<int>(homing::CommandResult::accepted)) {
        if (wait_cycle_end(c, shared, 120s, "home with a stuck sensor")) {
          const auto alarms = axis_alarms(c);
          if (!alarms.contains(a) || alarms.at(a) != static_cast<int>(homing::AlarmCode::sensor_not_found))
            shared.violation(fmt::format("sensor stuck inactive on {}: expected sensor_not_found, got {}", a,
                                         alarms_text(alarms)));
        }
      } else if (r) {
        shared.violation(fmt::format("home {} refused: {}", a, homing::command_result_name(static_cast<homing::CommandResult>(*r))));
      }
      c.must_write(sim(a, "fault"), 0);
      reset_and_check(c, shared, "after the stuck sensor");
      shared.last_event = "sensor stuck inactive on " + a + ", cleared, reset";
    } else {
      // Drive fault at rest: homing refused, reset refused while present, accepted after.
      if (!c.must_write(sim(a, "fault"), 4)) continue;
      ++c.stats.faults_injected;
      std::this_thread::sleep_for(20ms);
      auto r = command(c, "cmd.home_all");
      if (r && *r != static_cast<int>(homing::CommandResult::refused_drive_fault) &&
          *r != static_cast<int>(homing::CommandResult::refused_alarm))
        shared.violation(fmt::format("home all with a drive fault on {}: {}", a,
                                     homing::command_result_name(static_cast<homing::CommandResult>(*r))));
      r = command(c, "cmd.reset_alarm");
      if (r && *r != static_cast<int>(homing::CommandResult::refused_cause_present))
        shared.violation(fmt::format("reset with the drive fault still present: {}",
                                     homing::command_result_name(static_cast<homing::CommandResult>(*r))));
      c.must_write(sim(a, "fault"), 0);
      std::this_thread::sleep_for(20ms);
      reset_and_check(c, shared, "after the drive fault");
      shared.last_event = "drive fault on " + a + ", cleared, reset";
    }
  }
}

struct Owned {
  std::string name;
  std::int64_t lo, hi;
};

void writer_role(Client& c, Shared& shared, std::vector<Owned> regs, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  if (regs.empty()) return;
  while (!shared.stop) {
    const Owned& o = regs[std::uniform_int_distribution<std::size_t>(0, regs.size() - 1)(rng)];
    const std::int64_t v = std::uniform_int_distribution<std::int64_t>(o.lo, o.hi)(rng);
    const int rc = c.write(o.name, v);
    if (rc == 0) {
      if (auto back = c.read(o.name)) {
        if (*back != v) shared.violation(fmt::format("{} read back {} after writing {}", o.name, *back, v));
        else ++c.stats.writes_verified;
      }
    } else if (rc == 6) {
      c.expected_exception();  // a homing cycle runs: settings cannot change now
    } else {
      shared.violation(fmt::format("writing {} = {}: {}", o.name, v, c.last_error()));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(2, 20)(rng)));
  }
}

void poller_role(Client& c, Shared& shared, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::optional<std::uint16_t> last;
  auto changed_at = Clock::now();
  while (!shared.stop) {
    std::uint16_t st[10], axis[20];
    if (c.read_inputs(0, 10, st) && c.read_inputs(100 + 100 * static_cast<int>(rng() % 3), 20, axis)) {
      ++c.stats.polls;
      const std::uint16_t hb = st[5];
      if (!last || hb != *last) {
        last = hb;
        changed_at = Clock::now();
      } else if (Clock::now() - changed_at > 500ms) {
        shared.violation(fmt::format("status.heartbeat stuck at {} for more than 500 ms", hb));
        changed_at = Clock::now();
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(1, 15)(rng)));
  }
}

// ------------------------------------------------------------------ daemon
std::optional<long> vm_rss_kb(pid_t pid) {
  std::ifstream in(fmt::format("/proc/{}/status", pid));
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return std::nullopt;
}

int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

struct Spawned {
  pid_t pid = -1;
  int port = 0;
  std::filesystem::path dir;
};

Spawned spawn_daemon(const std::string& path, double time_scale) {
  Spawned s;
  std::string tmpl = (std::filesystem::temp_directory_path() / "homing-soak-XXXXXX").string();
  if (!::mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
  s.dir = tmpl;
  for (int attempt = 0; attempt < 5; ++attempt) {
    s.port = free_port();
    std::vector<std::string> argv{path, "--tcp", fmt::format("127.0.0.1:{}", s.port), "--db", (s.dir / "soak.db").string(),
                                  "--time-scale", fmt::format("{}", time_scale), "--log-level", "warn"};
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&fa, fds[1], 1);
    posix_spawn_file_actions_addopen(&fa, 2, (s.dir / "homingd.log").c_str(), O_WRONLY | O_CREAT | O_APPEND, 0600);
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    const int rc = ::posix_spawn(&s.pid, args[0], &fa, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    ::close(fds[1]);
    if (rc != 0) throw std::runtime_error(fmt::format("cannot start {}: {}", path, std::strerror(rc)));
    std::string got;
    const auto deadline = Clock::now() + 10s;
    bool ready = false;
    while (!ready && Clock::now() < deadline) {
      pollfd p{fds[0], POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char buf[256];
      const ssize_t n = ::read(fds[0], buf, sizeof buf);
      if (n <= 0) break;
      got.append(buf, static_cast<std::size_t>(n));
      ready = got.find("listening") != std::string::npos;
    }
    ::close(fds[0]);  // homingd prints nothing more on stdout
    if (ready) return s;
    ::kill(s.pid, SIGKILL);
    ::waitpid(s.pid, nullptr, 0);
  }
  throw std::runtime_error("homingd did not start (see " + (s.dir / "homingd.log").string() + ")");
}

double percentile(std::vector<float>& v, double p) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::size_t>(std::clamp(p * static_cast<double>(v.size() - 1), 0.0, static_cast<double>(v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"homing_soak: many Modbus clients against a running homingd for a bounded time, checking invariants.\n"
               "Exit 0 when no invariant was violated, 1 otherwise, 2 usage, 3 cannot reach the daemon."};
  std::string tcp = "127.0.0.1:1502", spawn_path;
  int clients = 8, unit = 1, sim_unit = 247;
  double duration_s = 20, time_scale = 10;
  std::uint64_t seed = 1;
  pid_t pid = 0;
  app.add_option("--tcp", tcp, "homingd address HOST:PORT")->capture_default_str();
  app.add_option("--clients", clients, "Modbus clients at once (at least 4)")->check(CLI::Range(4, 200))->capture_default_str();
  app.add_option("--duration-s", duration_s, "how long to run")->check(CLI::Range(1.0, 7.0 * 24 * 3600))->capture_default_str();
  app.add_option("--seed", seed, "random seed")->capture_default_str();
  app.add_option("--unit", unit, "module unit id")->capture_default_str();
  app.add_option("--sim-unit", sim_unit, "simulator unit id")->capture_default_str();
  app.add_option("--pid", pid, "homingd's PID, for its memory (VmRSS) at start and end");
  app.add_option("--spawn", spawn_path, "start this homingd (temporary database, free port) instead of --tcp");
  app.add_option("--time-scale", time_scale, "--time-scale of the spawned homingd")->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }

  std::optional<Spawned> daemon;
  std::string host = "127.0.0.1";
  int port = 1502;
  try {
    if (!spawn_path.empty()) {
      daemon = spawn_daemon(spawn_path, time_scale);
      port = daemon->port;
      pid = daemon->pid;
    } else {
      const auto colon = tcp.rfind(':');
      host = tcp.substr(0, colon);
      port = colon == std::string::npos ? 502 : std::stoi(tcp.substr(colon + 1));
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "homing_soak: {}\n", e.what());
    return 3;
  }
  const auto rss_start = pid > 0 ? vm_rss_kb(pid) : std::nullopt;

  Shared shared;
  std::vector<std::unique_ptr<Client>> cs;
  try {
    for (int i = 0; i < clients; ++i) cs.push_back(std::make_unique<Client>(host, port, i, shared, unit, sim_unit));
  } catch (const std::exception& e) {
    fmt::print(stderr, "homing_soak: {}\n", e.what());
    if (daemon) ::kill(daemon->pid, SIGKILL), ::waitpid(daemon->pid, nullptr, 0);
    return 3;
  }

  // Set-up: exact simulated edges (noise 0), seeks bounded for the stuck sensor.
  {
    Client& c = *cs[0];
    for (auto a : kHomed) {
      c.must_write(sim(a, "noise"), 0);
      c.must_write(sim(a, "fault"), 0);
      c.must_write(ax(a, "max_seek_travel"), 300000);
    }
    (void)command(c, "cmd.abort");
    std::this_thread::sleep_for(50ms);
    (void)command(c, "cmd.reset_alarm");
  }

  // Registers the writers own (one owner each, so a read-back is exact):
  // jog feedrates of the homing axes, settings of the disabled axes A B C.
  std::vector<Owned> pool;
  for (auto a : kHomed) pool.push_back({ax(a, "jog_feedrate"), 500, 3000});
  for (std::string_view a : {"a", "b", "c"}) {
    pool.push_back({ax(a, "pull_off"), 0, 5000});
    pool.push_back({ax(a, "home_position"), -10000, 10000});
    pool.push_back({ax(a, "seek_feedrate"), 200, 2000});
    pool.push_back({ax(a, "final_position"), -50000, 50000});
  }
  const int others = clients - 2;
  const int writers = std::max(1, others / 2);
  std::vector<std::vector<Owned>> owned(static_cast<std::size_t>(writers));
  for (std::size_t i = 0; i < pool.size(); ++i) owned[i % owned.size()].push_back(pool[i]);

  const auto t0 = Clock::now();
  std::vector<std::thread> threads;
  threads.emplace_back(cycle_role, std::ref(*cs[0]), std::ref(shared), seed * 7919 + 1);
  threads.emplace_back(fault_role, std::ref(*cs[1]), std::ref(shared), seed * 7919 + 2);
  for (int i = 2; i < clients; ++i) {
    const int k = i - 2;
    if (k < writers)
      threads.emplace_back(writer_role, std::ref(*cs[static_cast<std::size_t>(i)]), std::ref(shared),
                           owned[static_cast<std::size_t>(k)], seed * 7919 + static_cast<std::uint64_t>(i));
    else
      threads.emplace_back(poller_role, std::ref(*cs[static_cast<std::size_t>(i)]), std::ref(shared),
                           seed * 7919 + static_cast<std::uint64_t>(i));
  }
  while (Clock::now() - t0 < std::chrono::duration<double>(duration_s)) std::this_thread::sleep_for(100ms);
  shared.stop = true;
  for (auto& t : threads) t.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  const auto rss_end = pid > 0 ? vm_rss_kb(pid) : std::nullopt;

  Stats total;
  for (auto& c : cs) total.merge(c->stats);
  cs.clear();

  std::optional<int> exit_status;
  if (daemon) {
    ::kill(daemon->pid, SIGTERM);
    int st = 0;
    for (int i = 0; i < 300; ++i) {
      if (::waitpid(daemon->pid, &st, WNOHANG) == daemon->pid) {
        exit_status = st;
        break;
      }
      std::this_thread::sleep_for(50ms);
    }
    if (!exit_status) {
      ::kill(daemon->pid, SIGKILL);
      ::waitpid(daemon->pid, nullptr, 0);
      shared.violation("homingd did not exit within 15 s of SIGTERM");
    } else if (!WIFEXITED(*exit_status) || WEXITSTATUS(*exit_status) != 0) {
      shared.violation(fmt::format("homingd ended with status {} after SIGTERM (see {})", *exit_status,
                                   (daemon->dir / "homingd.log").string()));
    }
  }

  std::uint64_t errors = 0;
  for (const auto& [k, v] : total.errors) errors += v;
  fmt::print("homing_soak: {} clients for {:.1f} s (seed {})\n", clients, elapsed, seed);
  fmt::print("  {:<34} {}\n", "requests", total.requests);
  fmt::print("  {:<34} {:.0f}/s\n", "rate", total.requests / std::max(elapsed, 1e-9));
  fmt::print("  {:<34} {}\n", "errors", errors);
  for (const auto& [k, v] : total.errors) fmt::print("    {:<32} {}\n", k, v);
  fmt::print("  {:<34} {}\n", "exception 06 during homing (expected)", total.expected_busy);
  fmt::print("  {:<34} p50 {:.2f}  p90 {:.2f}  p99 {:.2f}  max {:.2f}\n", "latency ms", percentile(total.latency_ms, 0.5),
             percentile(total.latency_ms, 0.9), percentile(total.latency_ms, 0.99),
             total.latency_ms.empty() ? 0.0 : *std::max_element(total.latency_ms.begin(), total.latency_ms.end()));
  fmt::print("  {:<34} {}\n", "status polls", total.polls);
  fmt::print("  {:<34} {}\n", "settings writes read back", total.writes_verified);
  fmt::print("  {:<34} {}\n", "homing cycles completed", total.cycles_completed);
  fmt::print("  {:<34} {}\n", "homing cycles aborted", total.cycles_aborted);
  fmt::print("  {:<34} {}\n", "faults injected", total.faults_injected);
  auto rss = [](const std::optional<long>& v) { return v ? fmt::format("{} kB", *v) : std::string("unknown (--pid)"); };
  fmt::print("  {:<34} {} -> {}\n", "homingd VmRSS start -> end", rss(rss_start), rss(rss_end));
  if (daemon && exit_status) fmt::print("  {:<34} {}\n", "homingd exit after SIGTERM", WIFEXITED(*exit_status) ? WEXITSTATUS(*exit_status) : -1);
  fmt::print("  {:<34} {}\n", "invariant violations", shared.violation_count);
  for (const auto& v : shared.violations) fmt::print("    - {}\n", v);
  if (daemon && shared.violation_count == 0) {
    std::error_code ec;
    std::filesystem::remove_all(daemon->dir, ec);
  }
  return shared.violation_count == 0 ? 0 : 1;
}
