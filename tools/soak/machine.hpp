#pragma once
// Steps on the machine over Modbus that the roles share: commands that wait
// until the control loop took them, the end of a homing cycle, alarms, and the
// positions after a homing against the simulator's truth.
#include <array>
#include <chrono>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "counted_client.hpp"

namespace soak {

// The axes the soak homes; A, B and C stay disabled (their settings are the writers').
inline constexpr std::array<std::string_view, 3> kHomed = {"x", "y", "z"};

std::string ax(std::string_view axis, std::string_view field);   // "axis.x.pull_off"
std::string sim(std::string_view axis, std::string_view field);  // "sim.x.fault"

// Waits until the control loop published three new snapshots after heartbeat h0.
void let_loop_take(CountedClient& c, std::int64_t h0);

// Writes a command coil; the command result once the loop took it.
std::optional<int> command(CountedClient& c, const std::string& coil);

// Waits for the end of a homing cycle; false (and a violation) if it does not end.
bool wait_cycle_end(CountedClient& c, Shared& shared, std::chrono::seconds timeout, const std::string& what);

// Latched alarm code by axis letter, homed axes only.
std::map<std::string, int> axis_alarms(CountedClient& c);
std::string alarms_text(const std::map<std::string, int>& alarms);

// Resets the alarms; false (and a violation) when the machine stays in alarm.
bool reset_and_check(CountedClient& c, Shared& shared, const std::string& what);

// Positions after a successful homing against the simulator's truth (noise 0).
void check_truth(CountedClient& c, Shared& shared, const std::map<std::string, std::int64_t>& pull_off,
                 const std::map<std::string, std::int64_t>& home);

}  // namespace soak
