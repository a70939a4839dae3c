#pragma once
// What the engine reads each control period and what it emits.
#include <array>
#include <cstdint>
#include <optional>

#include "axes.hpp"
#include "motion.hpp"
#include "trust.hpp"

namespace homing {

// Timed transitions of a digital input during the period that just ended.
// Times are seconds from the start of that period (0..dt). A backend without
// timestamps reports only the level; the engine then places the edge at the
// middle of the period and the precision is ±v·dt/2.
struct InputEdges {
  static constexpr std::size_t kMax = 8;
  std::array<double, kMax> time_s{};
  std::uint8_t count = 0;
  bool overflow = false;  // more transitions than kMax happened (bounce storm)
  void add(double t) {
    if (count < kMax) time_s[count++] = t; else overflow = true;
  }
};

struct AxisInputs {
  bool sensor_level = false;    // electrical level of the home input now (before polarity)
  InputEdges sensor_edges{};
  bool index_level = false;
  InputEdges index_edges{};     // rising edges of the encoder index pulse
  bool absolute_valid = false;
  double absolute_position_mm = 0;  // absolute encoder reading
  bool drive_fault = false;
  bool stall = false;           // the drive's stall / torque-limit output (hard-stop homing)
  bool drive_done = false;      // the drive's home done: its own homing finished, its reference valid
  // Locking indexer: the pin is fully out (LinuxCNC joint.N.is-unlocked).
  // Only read on an axis with axis.<a>.indexer_lock.
  bool indexer_unlocked = false;
  // End-of-travel limit switches: electrical levels (before limits_nc). Only
  // read on an axis with axis.<a>.limits_fitted.
  bool limit_min_level = false;
  bool limit_max_level = false;
};

// Commands arrive as one-period requests (the runtime turns a coil write into
// one request). Jog is a level held by the runtime while its coil is held.
struct Commands {
  bool home_all = false;
  AxisMask home_axes = 0;
  AxisMask unhome_axes = 0;  // service: forget the reference of these axes (and their gantry partners)
  bool abort = false;
  bool reset_alarm = false;
  std::array<std::int8_t, kAxisCount> jog{};  // -1, 0, +1 while held
  AxisMask move_axes = 0;
  std::array<double, kAxisCount> move_target_mm{};
  // Service: give these unhomed axes a coordinate where they stand, without moving.
  AxisMask set_position_axes = 0;
  std::array<double, kAxisCount> set_position_mm{};
  AxisMask refcheck_axes = 0;  // reference check of these axes (trust.hpp), one cycle
  AxisMask measure_axes = 0;   // commissioning measurement of one axis (measure.hpp): home, then to the opposite end
};

// Two requests that arrive within one period, as one: flags and masks join,
// a later target or jog wins. Every field is here, so a new command cannot be
// dropped by a runtime that queues requests between periods.
inline void merge(Commands& into, const Commands& c) {
  into.home_all = into.home_all || c.home_all;
  into.home_axes |= c.home_axes;
  into.unhome_axes |= c.unhome_axes;
  into.refcheck_axes |= c.refcheck_axes;
  into.measure_axes |= c.measure_axes;
  into.abort = into.abort || c.abort;
  into.reset_alarm = into.reset_alarm || c.reset_alarm;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (c.jog[a] != 0) into.jog[a] = c.jog[a];
    if (c.move_axes & axis_bit(a)) into.move_target_mm[a] = c.move_target_mm[a];
    if (c.set_position_axes & axis_bit(a)) into.set_position_mm[a] = c.set_position_mm[a];
  }
  into.move_axes |= c.move_axes;
  into.set_position_axes |= c.set_position_axes;
}

struct Inputs {
  std::array<AxisInputs, kAxisCount> axes{};
  bool estop = false;
  bool start_button = false;
  bool homing_permit = false;
  // The host watchdog (global.watchdog_ms): host.heartbeat has not changed
  // within it (stale), and so motion started over Modbus must stop (lost).
  bool heartbeat_stale = false;
  bool communication_lost = false;
  bool settings_lost = false;       // set by the runtime when settings had to be reset
  Commands commands{};
  // Where each axis came to rest before this start, as the runtime kept it
  // (trust.hpp): given once, before anything moves. An axis whose last stop
  // was clean, in the frame its settings give it now, takes its stored
  // position as its coordinate and is offered a reference check.
  std::optional<LastStops> restore{};
};

struct AxisOutputs {
  MotionCommand motion{};        // what the pulse generator runs until the next period
  MotionState motor{};           // motor position/velocity now (for checks and step counting)
  bool enable = false;
  bool push_output = false;      // lowers motor current while pushing into the stop
  bool commutator_output = false;  // master axis only: route the output to the slave
  bool drive_request = false;    // asks the drive to home itself (drive mode, phase drive_homing)
  bool indexer_unlock = false;   // locking indexer: pull the pin out (LinuxCNC joint.N.unlock)
};

struct Outputs {
  std::array<AxisOutputs, kAxisCount> axes{};
  bool homing_done_lamp = false;
};

}  // namespace homing
