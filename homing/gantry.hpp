#pragma once
// Gantry pairs: which axes form one, and what a slave inherits from its master.
// The engine, the configuration check, the register validation and the tools
// all ask these functions, so the answer is the same everywhere.
#include <algorithm>
#include <cstddef>
#include <optional>
#include <string_view>

#include "settings.hpp"

namespace homing {

// The master of `axis` when axis is the slave of a pair that may move
// (passes the gantry rules: an enabled slave of an enabled switch-homing
// master that is no slave itself, the first slave of that master), else -1.
int gantry_master(const Settings& settings, std::size_t axis);
// The slave of `axis` when it is the master of a valid pair, else -1.
int gantry_slave(const Settings& settings, std::size_t axis);
// The other axis of a valid pair, else -1.
int gantry_partner(const Settings& settings, std::size_t axis);
bool is_commutator_slave(const Settings& settings, std::size_t axis);

// The settings each axis actually moves with. A slave homes with its master's
// motion settings (mode, direction, feedrates, travel and back-off limits,
// pre-move, push distance, index pitch, home and final position, jog feedrate,
// soft limits) and keeps only its own sensor settings (polarity, debounce,
// shared limit), pull-off (software-slaved only: a commutator pair pulls off
// on one output), switch compensation and max misalignment. Both axes of a
// pair move with the lower of their two accelerations, so neither drive is
// asked for more than it can do, in homing, jog, move and every stop.
Settings motion_settings(const Settings& settings);

// Whether a gantry slave moves with its master's value of this setting
// (motion_settings copies it) and nothing reads its own while it is a slave:
// writing it on the slave would change nothing, so the write path refuses
// it and names the master's register instead. The slave's own mode (which
// makes it a slave), sensor and limit-switch settings, indexer, acceleration
// (the pair takes the lower), switch compensation, max_misalignment,
// max_skew_change and refcheck_tolerance are its own; its pull-off too,
// unless a commutator pair pulls off on one output.
bool inherited_from_master(AxisField field, SlaveMode mode);

// The kind an axis moves with: its own axis.<a>.kind, or, for a slave (any
// axis whose slave_of names another axis), its master's, like its other
// motion settings: a slave's own kind is not used while it is a slave. It
// names the unit of every value of the axis, everywhere: alarm texts,
// settings faults, the log, homingctl, the settings file, the tag files made
// for a machine.
AxisKind axis_kind(const Settings& settings, std::size_t axis);
// "mm" or "deg": the unit of a length on the axis (feedrates per min,
// accelerations per s²).
std::string_view axis_unit(const Settings& settings, std::size_t axis);

// What an external-commutator slave homes with when its motor runs alone,
// from its motion settings: it only corrects the gantry's skew from its
// master's reference edge, slowly (seek at the latch feedrate), on its own
// switch edge (no pre-move, push, index or final move), never further than
// the allowed misalignment from square (its seek is bounded by that:
// search_phases.cpp, travel_within_square).
AxisSettings commutator_slave_homing(AxisSettings pair_motion);

// Where a gantry pair may stand during a cycle, in slave − master motor
// position: within max_misalignment of square (where the pair was last
// assigned its home, else where the cycle found it), widened to the rack
// the cycle started with, so that a pair an alarm left racked may come back
// to square and up to the limit beyond, and a pair found further out (the
// limit lowered since) may stay as far out on its own side. The gantry
// guard (gantry_guard.cpp) and a commutator slave's lone seek
// (search_phases.cpp) both hold the pair to it.
struct SquareBand {
  double square_mm = 0;         // slave − master where the pair is square
  double rack_at_start_mm = 0;  // how far from square the cycle found it
  double low_mm = 0;            // the furthest off square allowed, each way
  double high_mm = 0;
  double off_square(double slave_mm, double master_mm) const { return slave_mm - master_mm - square_mm; }
  bool within(double off) const { return off >= low_mm && off <= high_mm; }
};
inline SquareBand square_band(std::optional<double> square_mm, double rel_at_start_mm, double limit_mm) {
  SquareBand b;
  b.square_mm = square_mm.value_or(rel_at_start_mm);
  b.rack_at_start_mm = rel_at_start_mm - b.square_mm;
  b.low_mm = std::min(-limit_mm, b.rack_at_start_mm - 1e-9);
  b.high_mm = std::max(limit_mm, b.rack_at_start_mm + 1e-9);
  return b;
}

}  // namespace homing
