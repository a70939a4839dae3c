#pragma once
// Knobs of the simulated machine: the spec's sim.<a>.* registers in engineering
// units (mm, or deg on rotary axes).
#include <array>
#include <cstdint>
#include <span>

#include "homing/axes.hpp"
#include "homing/enum_info.hpp"

namespace homing::sim {

// Numeric values are the sim.<a>.fault register values: never renumber.
enum class Fault : std::uint8_t {
  none = 0,
  sensor_stuck_active = 1,
  sensor_stuck_inactive = 2,
  wire_break = 3,
  drive_fault = 4,
  indexer_stuck_locked = 5,  // the indexer's pin goes in and stays in, whatever the unlock output says
  indexer_never_locks = 6,   // the pin stays out once out: the indexer never reports locked again
};
inline constexpr EnumInfo<Fault> kFaultInfo[] = {
    {Fault::none, "none", "no fault"},
    {Fault::sensor_stuck_active, "sensor_stuck_active", "sensor reads active everywhere"},
    {Fault::sensor_stuck_inactive, "sensor_stuck_inactive", "sensor never turns active"},
    {Fault::wire_break, "wire_break", "sensor wire broken (NC reads active, NO never)"},
    {Fault::drive_fault, "drive_fault", "the drive reports a fault"},
    {Fault::indexer_stuck_locked, "indexer_stuck_locked",
     "the locking indexer's pin goes in (at once, even under motion) and never comes out"},
    {Fault::indexer_never_locks, "indexer_never_locks", "the locking indexer's pin, once out, never goes in again"},
};
static_assert(lists_every_value(kFaultInfo, Fault::indexer_never_locks));
constexpr std::span<const EnumInfo<Fault>> enum_table(Fault) { return kFaultInfo; }

struct AxisConfig {
  double actual_position_mm = 0;  // where the carriage starts / is placed
  double sensor_min_mm = 0, sensor_max_mm = 0;  // cam holding the home sensor active; max < min = no cam
  double hysteresis_mm = 0;
  double noise_mm = 0;            // std deviation of each edge's position
  double bounce_ms = 0;           // contact bounce after each edge
  bool sensor_nc = false;         // how the simulated switch is wired
  double hard_stop_min_mm = -1e9, hard_stop_max_mm = 1e9;  // mechanical stops
  double index_pitch_mm = 0;      // 0 = no index
  double index_offset_mm = 0;
  double absolute_offset_mm = 0;  // absolute encoder reads actual + offset
  Fault fault = Fault::none;
  // Locking indexer (when fitted, MachineConfig::indexer): time from the
  // unlock output's change to the pin being out / in.
  double unlock_delay_ms = 0;
  double lock_delay_ms = 0;
};

struct MachineConfig {
  std::array<AxisConfig, kAxisCount> axes{};
  std::uint64_t seed = 1;
  // commutator_slave[m] = s when axis s is an external-commutator slave of master m (else -1).
  std::array<int, kAxisCount> commutator_slave{-1, -1, -1, -1, -1, -1};
  // indexer[a]: axis a has a locking indexer (its pin holds the carriage
  // while in; its unlocked input reports the pin out).
  std::array<bool, kAxisCount> indexer{};
};

}  // namespace homing::sim
