#pragma once
// Encoder index pulses at actual positions offset + k * pitch.
#include "homing/io.hpp"
#include "homing/motion.hpp"

namespace homing::sim {

// Adds the time of every index position the monotonic piece passes. A position
// is counted where the carriage arrives on it, so a turn exactly on a pulse
// counts once.
void add_index_crossings(const MotionPiece& piece, double pitch_mm, double offset_mm,
                         InputEdges& edges);

}  // namespace homing::sim
