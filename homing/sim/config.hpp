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
  stall_dead = 5,     // the drive's stall output never turns on
  stall_stuck = 6,    // the drive's stall output is on all the time
  drive_never_answers = 7,     // drive mode: on the home request the drive drops home done and never finishes
  drive_answers_at_once = 8,   // drive mode: home done on at once on the request, without homing
  drive_done_lost = 9,         // drive mode: home done held off (lost reference, broken wire)
  indexer_stuck_locked = 10, // the indexer's pin goes in and stays in, whatever the unlock output says
  indexer_never_locks = 11,  // the pin stays out once out: the indexer never reports locked again
  limits_dead = 12,          // neither limit switch ever reports (NO wiring cut, switches jammed open)
  limits_stuck = 13,         // both limit switches report active everywhere
  encoder_reversed = 14,     // the encoder counts the wrong way: it reads absolute_offset - actual position
};
inline constexpr EnumInfo<Fault> kFaultInfo[] = {
    {Fault::none, "none", "no fault"},
    {Fault::sensor_stuck_active, "sensor_stuck_active", "sensor reads active everywhere"},
    {Fault::sensor_stuck_inactive, "sensor_stuck_inactive", "sensor never turns active"},
    {Fault::wire_break, "wire_break", "sensor wire broken (NC reads active, NO never)"},
    {Fault::drive_fault, "drive_fault", "the drive reports a fault"},
    {Fault::stall_dead, "stall_dead", "the drive's stall output never turns on"},
    {Fault::stall_stuck, "stall_stuck", "the drive's stall output is on all the time"},
    {Fault::drive_never_answers, "drive_never_answers",
     "the drive starts homing on the home request (drops home done) but never finishes"},
    {Fault::drive_answers_at_once, "drive_answers_at_once", "the drive reports home done at once, without homing"},
    {Fault::drive_done_lost, "drive_done_lost",
     "the drive's home done goes off and stays off (lost reference, broken wire)"},
    {Fault::indexer_stuck_locked, "indexer_stuck_locked",
     "the locking indexer's pin goes in (at once, even under motion) and never comes out"},
    {Fault::indexer_never_locks, "indexer_never_locks", "the locking indexer's pin, once out, never goes in again"},
    {Fault::limits_dead, "limits_dead", "neither end-of-travel limit switch ever turns active"},
    {Fault::limits_stuck, "limits_stuck", "both end-of-travel limit switches read active everywhere"},
    {Fault::encoder_reversed, "encoder_reversed",
     "the encoder counts the wrong way (its channels swapped): it reads the offset less the carriage's position"},
};
static_assert(lists_every_value(kFaultInfo, Fault::encoder_reversed));
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
  // The encoder's counts: it reads in steps of its resolution, each reading
  // off by normal noise of this standard deviation (drawn from the seed).
  // 0 and 0, the default, read exactly. Against a mechanical stop it reads
  // where the carriage is held while the steps go on.
  double encoder_resolution_mm = 0;
  double encoder_noise_mm = 0;
  // The drive's stall output: on once the carriage has been held by a
  // mechanical stop, with the motor driving into it, for the detection time
  // plus a random share of the spread (drawn per contact); off when the
  // motor no longer drives into the stop.
  double stall_detect_ms = 20;
  double stall_spread_ms = 10;
  // The drive's own homing (drive mode): on the home request it moves the
  // carriage itself to its home at its own speed, waits, then reports done.
  double drive_home_position_mm = 0;       // where its homing ends (its own home sensor)
  double drive_speed_mm_per_min = 600;
  double drive_answer_ms = 100;            // after arriving, before home done
  Fault fault = Fault::none;
  // Locking indexer (when fitted, MachineConfig::indexer): time from the
  // unlock output's change to the pin being out / in.
  double unlock_delay_ms = 0;
  double lock_delay_ms = 0;
  // End-of-travel limit switches: active with the carriage at or below
  // limit_min_mm, at or above limit_max_mm (their cams run on to the
  // mechanical stops). Outside the stops they never trip.
  double limit_min_mm = -1e9, limit_max_mm = 1e9;
  bool limits_nc = false;         // how the simulated limit switches are wired
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
