#pragma once
// What the engine reports each period. Enum values are register values.
#include <array>
#include <cstdint>
#include <string_view>

#include "alarms.hpp"
#include "axes.hpp"
#include "phases.hpp"

namespace homing {

enum class MachineState : std::uint8_t { not_homed = 0, homing = 1, homed = 2, alarm = 3, moving = 4 };

enum class CommandResult : std::uint8_t {
  none = 0,
  accepted = 1,
  already_running = 2,       // the same command is still running; not restarted
  refused_alarm = 3,         // an alarm is latched: reset first
  refused_estop = 4,
  refused_drive_fault = 5,
  refused_busy = 6,          // another homing cycle or motion is running
  refused_not_homed = 7,     // not allowed before homing (global.allowed_without_homing)
  refused_no_permit = 8,     // global.permit_required and the permit is off
  refused_soft_limit = 9,    // target outside the soft limits
  refused_slave_axis = 10,   // a slave axis is commanded through its master
  refused_cause_present = 11,  // reset refused: e-stop, drive fault or watchdog still active
  refused_invalid = 12,      // the command itself makes no sense (bad axis, bad target)
  refused_communication_lost = 13,
  refused_settings_fault = 14,  // the configuration check refused the cycle: see the axis alarm
  refused_hard_limit = 15,   // on a tripped shared limit: only a jog away from the sensor is allowed
};
inline constexpr std::uint8_t kCommandResultCount = 16;

// status.interlocks: what blocks homing or motion now; 0 = free to move.
namespace interlock {
inline constexpr std::uint16_t estop = 1u << 0;
inline constexpr std::uint16_t drive_fault = 1u << 1;
inline constexpr std::uint16_t alarm_latched = 1u << 2;
inline constexpr std::uint16_t settings_lost = 1u << 3;
inline constexpr std::uint16_t communication_lost = 1u << 4;
inline constexpr std::uint16_t permit_missing = 1u << 5;
inline constexpr std::uint16_t not_homed = 1u << 6;       // motion limited until homed
inline constexpr std::uint16_t homing_active = 1u << 7;
inline constexpr std::uint16_t motion_active = 1u << 8;   // jog or move running
inline constexpr int kCount = 9;
}  // namespace interlock

std::string_view state_name(MachineState s);
std::string_view command_result_name(CommandResult r);
std::string_view interlock_name(int bit);

struct AxisStatus {
  Phase phase = Phase::idle;
  Alarm alarm{};
  double position_mm = 0;           // machine coordinates
  double velocity_mm_per_s = 0;
  bool homed = false;
  bool sensor = false;              // home sensor active (debounced, polarity applied)
  bool busy = false;
  double trigger_position_mm = 0;   // reference edge, in the coordinates believed before assign
  double home_correction_mm = 0;    // assigned - believed at the reference edge
  double stop_distance_mm = 0;      // v²/2a of the seek
  double phase_distance_mm = 0;     // travelled in the current phase
};

struct Status {
  MachineState state = MachineState::not_homed;
  std::uint8_t sequence_step = 0;  // 1..6 while homing, 0 otherwise
  std::uint32_t homing_cycles = 0;  // cycles completed successfully
  std::uint32_t heartbeat = 0;      // control periods since start
  CommandResult last_command_result = CommandResult::none;
  std::uint32_t command_count = 0;  // commands judged so far: last_command_result belongs to the latest
  std::uint16_t interlocks = 0;
  AlarmCode global_alarm = AlarmCode::none;  // alarm not tied to one axis (e-stop at rest, settings lost)
  bool alarm = false;
  bool homing = false;
  bool estop = false;
  std::array<AxisStatus, kAxisCount> axes{};
};

}  // namespace homing
