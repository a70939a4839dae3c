#include "machine.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <thread>

#include "homing/alarms.hpp"
#include "homing/status.hpp"

namespace soak {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

std::string ax(std::string_view a, std::string_view f) { return fmt::format("axis.{}.{}", a, f); }
std::string sim(std::string_view a, std::string_view f) { return fmt::format("sim.{}.{}", a, f); }

// Waits until the control loop published three new snapshots, so it took a
// command just written (its mailbox is taken with try_lock; with --time-scale
// the heartbeat counts several engine steps per period).
void let_loop_take(CountedClient& c, std::int64_t h0) {
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
std::optional<int> command(CountedClient& c, const std::string& coil) {
  const auto h0 = c.read("status.heartbeat");
  if (!h0 || !c.must_write(coil, 1)) return std::nullopt;
  let_loop_take(c, *h0);
  auto r = c.read("status.last_command_result");
  return r ? std::optional<int>(static_cast<int>(*r)) : std::nullopt;
}

// Waits for the end of a homing cycle; false (and a violation) if it does not end.
bool wait_cycle_end(CountedClient& c, Shared& shared, std::chrono::seconds timeout, const std::string& what) {
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

std::map<std::string, int> axis_alarms(CountedClient& c) {
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

bool reset_and_check(CountedClient& c, Shared& shared, const std::string& what) {
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
void check_truth(CountedClient& c, Shared& shared, const std::map<std::string, std::int64_t>& pull_off,
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

}  // namespace soak
