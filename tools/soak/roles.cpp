#include "roles.hpp"

#include <fmt/format.h>

#include <chrono>
#include <map>
#include <optional>
#include <random>
#include <thread>

#include "homing/alarms.hpp"
#include "homing/status.hpp"
#include "machine.hpp"

namespace soak {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

void cycle_role(CountedClient& c, Shared& shared, std::uint64_t seed) {
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

void fault_role(CountedClient& c, Shared& shared, std::uint64_t seed) {
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

void writer_role(CountedClient& c, Shared& shared, std::vector<Owned> regs, std::uint64_t seed) {
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

void poller_role(CountedClient& c, Shared& shared, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::optional<std::uint16_t> last;
  auto changed_at = Clock::now();
  while (!shared.stop) {
    const auto st = c.read_inputs(0, 10);
    if (st && c.read_inputs(100 + 100 * static_cast<int>(rng() % 3), 20)) {
      ++c.stats.polls;
      const std::uint16_t hb = (*st)[5];
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

}  // namespace soak
