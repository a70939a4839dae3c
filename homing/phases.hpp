#pragma once
// What one axis is doing. Values are register values (axis.<a>.phase).
#include <cstdint>
#include <string_view>

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
};

std::string_view phase_name(Phase phase);

}  // namespace homing
