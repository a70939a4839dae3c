#pragma once
// The machine's status read over Modbus, as a table for people and JSON for scripts.
#include <array>
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "connection.hpp"
#include "homing/settings.hpp"
#include "homing/status.hpp"

namespace homingctl {

struct AxisView {
  homing::Phase phase = homing::Phase::idle;
  homing::AlarmCode alarm = homing::AlarmCode::none;
  homing::Phase alarm_phase = homing::Phase::idle;
  double alarm_value = 0;  // axis.<a>.alarm_value: distance travelled, misalignment, ...
  homing::GantrySide alarm_side = homing::GantrySide::none;  // misalignment: the side at fault
  double alarm_rack_at_start = 0;  // misalignment: how far out of square the cycle found the pair
  std::uint8_t alarm_rule = 0;     // axis.<a>.alarm_rule: a limit alarm's end (1 negative, 2 positive), ...
  double position = 0, velocity = 0, phase_distance = 0, stop_distance = 0;
  bool homed = false, sensor = false, busy = false;
  bool limit_min = false, limit_max = false;  // the end-of-travel limit switches read active
  homing::Trust trust = homing::Trust::unknown;  // axis.<a>.trust
  double refcheck_error = 0;                    // axis.<a>.refcheck_error: the last reference check's figure
};

struct StatusView {
  homing::MachineState state = homing::MachineState::not_homed;
  int sequence_step = 0;
  std::uint32_t homing_cycles = 0;
  std::uint16_t heartbeat = 0;
  homing::CommandResult last_command_result = homing::CommandResult::none;
  std::uint16_t interlocks = 0;
  homing::AlarmCode global_alarm = homing::AlarmCode::none;
  bool alarm = false, homing = false, estop = false;
  std::array<AxisView, homing::kAxisCount> axes{};
};

// Axis registers are read only for axes whose mode is not disabled.
StatusView read_status(Connection& c, const homing::Settings& settings);

// The sentence for an axis alarm (describe_alarm; settings faults re-checked locally).
std::string alarm_text(std::size_t axis, const AxisView& a, const homing::Settings& settings);
std::string global_alarm_text(homing::AlarmCode code, const homing::Settings& settings);
// "e-stop, alarm latched" or "none".
std::string interlocks_text(std::uint16_t bits);

std::string render_status(const StatusView& s, const homing::Settings& settings, bool progress);
// One line of what a running cycle does now ("step 1: X seek 12.3 / 250 mm, Y seek ..."),
// without the distances when `distances` is false; empty when nothing moves.
std::string progress_line(const StatusView& s, const homing::Settings& settings, bool distances);
nlohmann::json status_json(const StatusView& s, const homing::Settings& settings);

// Bound of the phase an axis is in (for a progress bar), 0 if none.
double phase_bound_mm(homing::Phase phase, const homing::AxisSettings& s);
std::string progress_bar(double done, double bound, int width);

}  // namespace homingctl
