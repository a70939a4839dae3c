#pragma once
// What one axis is doing. Values are register values (axis.<a>.phase).
#include <cstdint>
#include <span>
#include <string_view>

#include "enum_info.hpp"

namespace homing {

enum class Phase : std::uint8_t {
  idle = 0,
  waiting = 1,        // in a later sequence step, or waiting for its gantry partner
  pre_move = 2,
  seek = 3,
  stop = 4,           // decelerating after the trigger; the sensor must stay active
  push = 5,           // pushing into the mechanical stop with the push output on
  back_off = 6,
  reapproach = 7,
  index = 8,
  pull_off = 9,
  assign = 10,
  final_move = 11,
  align_slave = 12,   // external commutator: the slave motor alone finds its edge
  done = 13,
  jog = 14,
  move = 15,
  stopping = 16,      // decelerating after an alarm or abort
  clear_sensors = 17, // gantry: both sides move off their sensors together before the seek
  push_to_stop = 18,  // hard-stop homing: pushing toward the mechanical stop until the drive stalls
  drive_homing = 19,  // the drive homes itself: home request on, waiting for its home done
  unlock = 20,        // locking indexer: unlock output on, motion held until it reports unlocked
  lock = 21,          // locking indexer: at rest, unlock output off, waiting for it to lock
  cam_seek = 22,      // home cam in mid-travel: seeking the cam, reversing at the limit switch ahead
  limit_reversal = 23,  // home cam: braking at the limit switch, then seeking the cam the other way
  cam_stop = 24,      // home cam: decelerating after the cam's trigger; the cam must stay active
  cam_latch = 25,     // home cam: leaving the cam at latch_feedrate toward its reference edge
  reference_check = 26,  // after a restart: finding the switch edge near where the stored position puts it
  return_to_start = 27,  // failure policy return_to_start: braking, then back to where the cycle found it
  measure_travel = 28,   // commissioning measurement: from home at latch feedrate to the opposite end of travel
};

inline constexpr EnumInfo<Phase> kPhaseInfo[] = {
    {Phase::idle, "idle", "at rest, no command running"},
    {Phase::waiting, "waiting",
     "waiting for a later sequence step or for its gantry partner (after a failure: for its step's turn to return)"},
    {Phase::pre_move, "pre_move", "moving pre_move_distance away from the sensor before the seek"},
    {Phase::seek, "seek", "searching for the home sensor at seek_feedrate"},
    {Phase::stop, "stop", "decelerating after the trigger"},
    {Phase::push, "push", "pushing into the mechanical stop"},
    {Phase::back_off, "back_off", "backing off at latch_feedrate until the sensor releases"},
    {Phase::reapproach, "reapproach", "approaching the sensor again at latch_feedrate"},
    {Phase::index, "index", "continuing to the next encoder index pulse"},
    {Phase::pull_off, "pull_off", "moving pull_off away from the reference edge"},
    {Phase::assign, "assign", "at rest: home_position is assigned"},
    {Phase::final_move, "final_move", "moving to final_position"},
    {Phase::align_slave, "align_slave", "external commutator: the slave finds its own edge"},
    {Phase::done, "done", "the cycle of this axis completed (axis.<a>.homed says whether it still counts as homed)"},
    {Phase::jog, "jog", "jogging"},
    {Phase::move, "move", "moving to a commanded target"},
    {Phase::stopping, "stopping", "decelerating after an alarm or abort"},
    {Phase::clear_sensors, "clear_sensors",
     "gantry: both sides move off their sensors together (latch feedrate) before the seek"},
    {Phase::push_to_stop, "push_to_stop",
     "hard-stop homing: moving into the mechanical stop at reduced current until the drive reports a stall"},
    {Phase::drive_homing, "drive_homing",
     "the drive homes itself: home request on, waiting for its home done within drive_home_timeout"},
    {Phase::unlock, "unlock", "locking indexer: unlocking before the axis moves (motion held until unlocked)"},
    {Phase::lock, "lock", "locking indexer: at rest, locking again"},
    {Phase::cam_seek, "cam_seek",
     "home cam in mid-travel: seeking the cam at seek_feedrate in direction (reverses at the limit switch)"},
    {Phase::limit_reversal, "limit_reversal",
     "home cam: met the limit switch first; braking, then seeking the cam the other way"},
    {Phase::cam_stop, "cam_stop", "home cam: decelerating on the cam after its trigger"},
    {Phase::cam_latch, "cam_latch", "home cam: leaving the cam at latch_feedrate across its reference edge"},
    {Phase::reference_check, "reference_check",
     "reference check: finding the switch edge at latch_feedrate near where the stored position puts it, then "
     "back to where the check started"},
    {Phase::return_to_start, "return_to_start",
     "the cycle failed (global.failure_policy return_to_start): braking, then moving back to where the cycle found "
     "the axis, at the lower of jog_feedrate and seek_feedrate"},
    {Phase::measure_travel, "measure_travel",
     "commissioning measurement (cmd.measure.<a>): homed, travelling at latch_feedrate away from home to the "
     "opposite limit switch (then just off it) or hard stop, within max_seek_travel"},
};
static_assert(lists_every_value(kPhaseInfo, Phase::measure_travel));
constexpr std::span<const EnumInfo<Phase>> enum_table(Phase) { return kPhaseInfo; }

std::string_view phase_name(Phase phase);

// The phases that meet an end-of-travel limit switch on purpose (home_cam's
// search reverses there); in every other phase an active one is a hard limit.
constexpr bool reverses_at_limits(Phase p) { return p == Phase::cam_seek || p == Phase::limit_reversal; }

}  // namespace homing
