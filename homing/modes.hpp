#pragma once
// The homing methods, one row each: what a method needs wired, the phases it
// runs in order, the coordinate it defines and where it may stand in a
// gantry. The phase runner, the rule set, homingctl's check, the GPIO wiring
// check, the mode register's value list and the generated maps all read this
// table; nothing else decides what a mode does. Adding a method is its row
// here plus its phase functions (and the simulator's model of a new input).
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "enum_info.hpp"
#include "phases.hpp"

namespace homing {

// Numeric values are register values (axis.<a>.mode): never renumber.
enum class HomingMode : std::uint8_t {
  disabled = 0,
  manual = 1,
  switch_release = 2,
  switch_reapproach = 3,
  switch_index = 4,
  absolute = 5,
  absolute_final = 6,
  pushing_release = 7,
  pushing_reapproach = 8,
  hard_stop = 9,
  drive = 10,
  home_cam = 11,
};

// What a method needs wired to the axis, one bit each.
enum class Signal : std::uint16_t {
  step_output = 1u << 0,       // the axis moves: step/dir (or a drive's motion input)
  home_sensor = 1u << 1,       // the home switch or sensor
  index = 1u << 2,             // the encoder's index pulse
  push_output = 1u << 3,       // reduces the motor current while pushing into the stop
  absolute_encoder = 1u << 4,  // the absolute position (and its valid flag)
  stall = 1u << 5,             // the drive's stall / torque-limit output
  drive_request = 1u << 6,     // output: asks the drive to run its own homing procedure
  drive_done = 1u << 7,        // input: the drive reports its homing done (its reference is valid)
  limit_min = 1u << 8,         // input: end-of-travel limit switch at the negative end
  limit_max = 1u << 9,         // input: end-of-travel limit switch at the positive end
};
using Signals = std::uint16_t;
constexpr Signals operator|(Signal a, Signal b) {
  return static_cast<Signals>(static_cast<Signals>(a) | static_cast<Signals>(b));
}
constexpr Signals operator|(Signals a, Signal b) { return static_cast<Signals>(a | static_cast<Signals>(b)); }

struct SignalInfo {
  Signal signal;
  std::string_view name;  // the line's name in the [gpiod] table, where it is a GPIO line
  std::string_view text;
  std::string_view use;     // what a mode that needs it does: "axis.x.mode 2 <use>"
  bool gpio_line_required;  // the GPIO backend refuses a mode that needs it without its line
};
inline constexpr SignalInfo kSignalInfo[] = {
    {Signal::step_output, "step", "step/dir output (the axis moves)", "can move", true},
    {Signal::home_sensor, "home", "home switch or sensor input", "homes on a switch", true},
    {Signal::index, "index", "encoder index pulse input", "homes on the encoder's index pulse", true},
    // Without a push line the push runs at full current: allowed, as it was.
    {Signal::push_output, "push", "reduced-current output while pushing", "pushes into a stop", false},
    // Not a GPIO line: read from the drive or encoder interface.
    {Signal::absolute_encoder, "absolute", "absolute encoder position", "reads an absolute encoder", false},
    {Signal::stall, "stall", "the drive's stall or torque-limit output", "homes on the drive's stall output", true},
    {Signal::drive_request, "home_request", "home request output to the drive", "has the drive home itself", true},
    {Signal::drive_done, "home_done", "home done input from the drive", "waits for the drive's home done", true},
    {Signal::limit_min, "limit_min", "end-of-travel limit switch at the negative end",
     "reverses its search at the limit switches", true},
    {Signal::limit_max, "limit_max", "end-of-travel limit switch at the positive end",
     "reverses its search at the limit switches", true},
};

// How a method that pushes into a mechanical stop tells that the carriage has
// stopped (axis.<a>.stall_detect). Values are register values: never renumber.
enum class StallDetect : std::uint8_t { stall_input = 0, following_error = 1 };
inline constexpr EnumInfo<StallDetect> kStallDetectInfo[] = {
    {StallDetect::stall_input, "stall_input", "the drive's stall or torque-limit input turns on"},
    {StallDetect::following_error, "following_error",
     "the encoder: the carriage falls behind its steps by more than max_following_error"},
};
static_assert(lists_every_value(kStallDetectInfo, StallDetect::following_error));
constexpr std::span<const EnumInfo<StallDetect>> enum_table(StallDetect) { return kStallDetectInfo; }
inline constexpr std::size_t kStallDetectCount = std::size(kStallDetectInfo);

// The coordinate a method gives the axis once homed.
enum class Coordinate : std::uint8_t {
  none,              // does not home: counts as homed where it stands, keeps its coordinate
  here,              // home_position where the axis stands, without moving
  reference_edge,    // home_position at the reference edge, pull-off (and a slave's compensation) away
  absolute_encoder,  // the encoder's reading minus home_position (home_position is the encoder's offset)
  mechanical_stop,   // home_position pull-off away from the mechanical stop the carriage was pushed against
  drive_reference,   // home_position where the drive, homing itself, reported done (and the axis rests)
};

enum class FinalMove : std::uint8_t {
  never,
  if_enabled,  // when axis.<a>.final_move_enable is set
  always,
};

inline constexpr std::size_t kMaxModePhases = 9;

// Drive mode: a home done sooner than this after the home request cannot
// follow a homing (a drive needs longer to start, search and stop even when
// already on its sensor): the drive did not home (drive_answered_at_once).
inline constexpr double kDriveMinHomingTime_s = 0.05;

struct ModeRow {
  HomingMode value;
  std::string_view name;  // register value name, logs, exports
  std::string_view text;
  Signals needs;
  // The homing phases of the axis on its own, in order. A gantry partner may
  // wait between them (Phase::waiting) and a gantry on its sensors clears
  // them first (Phase::clear_sensors, in place of the pre-move).
  std::array<Phase, kMaxModePhases> phases;
  std::uint8_t phase_count;
  Coordinate coordinate;
  FinalMove final_move;
  bool gantry_master;  // may be the master of a gantry pair
  bool gantry_slave;   // may be a gantry slave (it squares on its own sensor)
  bool shares_limit;   // its home sensor may double as a hard limit (axis.<a>.shared_limit)
  // A method that pushes into a mechanical stop finds it by one signal of
  // these, chosen per axis by axis.<a>.stall_detect (indexed by StallDetect),
  // on top of `needs`; none for the other methods.
  std::array<Signals, kStallDetectCount> stop_signals{};

  constexpr std::span<const Phase> phase_list() const { return {phases.data(), phase_count}; }
  constexpr bool runs(Phase p) const {
    for (std::size_t i = 0; i < phase_count; ++i)
      if (phases[i] == p) return true;
    return false;
  }
  // The phase after `p` in this method, Phase::done after the last.
  constexpr Phase after(Phase p) const {
    for (std::size_t i = 0; i + 1 < phase_count; ++i)
      if (phases[i] == p) return phases[i + 1];
    return Phase::done;
  }
  constexpr Phase first() const { return phase_count > 0 ? phases[0] : Phase::done; }
  // Needed whatever the axis's settings say.
  constexpr bool needs_signal(Signal s) const { return (needs & static_cast<Signals>(s)) != 0; }
  // The method finds a mechanical stop by a signal axis.<a>.stall_detect chooses.
  constexpr bool detects_stop() const { return stop_signals[0] != 0; }
  // Everything it needs wired with this stop detection.
  constexpr Signals needs_with(StallDetect d) const {
    const auto i = static_cast<std::size_t>(d);
    return static_cast<Signals>(needs | (i < kStallDetectCount ? stop_signals[i] : stop_signals[0]));
  }
  constexpr bool needs_signal(Signal s, StallDetect d) const {
    return (needs_with(d) & static_cast<Signals>(s)) != 0;
  }
};

namespace mode_phases {
using P = Phase;
inline constexpr std::array<Phase, kMaxModePhases> none{};
inline constexpr std::array<Phase, kMaxModePhases> manual{P::assign, P::final_move};
inline constexpr std::array<Phase, kMaxModePhases> absolute{P::assign};
inline constexpr std::array<Phase, kMaxModePhases> release{P::pre_move, P::seek,     P::stop,   P::back_off,
                                                           P::pull_off, P::assign,   P::final_move};
inline constexpr std::array<Phase, kMaxModePhases> reapproach{P::pre_move,   P::seek,     P::stop,
                                                              P::back_off,   P::reapproach, P::pull_off,
                                                              P::assign,     P::final_move};
inline constexpr std::array<Phase, kMaxModePhases> index{P::pre_move, P::seek,     P::stop,   P::back_off,
                                                         P::index,    P::pull_off, P::assign, P::final_move};
inline constexpr std::array<Phase, kMaxModePhases> push_release{P::pre_move, P::seek,     P::stop,
                                                                P::push,     P::back_off, P::pull_off,
                                                                P::assign,   P::final_move};
inline constexpr std::array<Phase, kMaxModePhases> hard_stop{P::pre_move, P::push_to_stop, P::pull_off, P::assign,
                                                             P::final_move};
inline constexpr std::array<Phase, kMaxModePhases> push_reapproach{P::pre_move,   P::seek,     P::stop,
                                                                   P::push,       P::back_off, P::reapproach,
                                                                   P::pull_off,   P::assign,   P::final_move};
inline constexpr std::array<Phase, kMaxModePhases> drive{P::drive_homing, P::assign, P::final_move};
inline constexpr std::array<Phase, kMaxModePhases> home_cam{P::cam_seek,  P::limit_reversal, P::cam_stop, P::cam_latch,
                                                            P::pull_off,  P::assign,         P::final_move};
}  // namespace mode_phases

inline constexpr ModeRow kModeTable[] = {
    // clang-format off
    {HomingMode::disabled, "disabled", "does not home; counts as homed",
     0, mode_phases::none, 0, Coordinate::none, FinalMove::never, false, false, true},
    {HomingMode::manual, "manual", "no movement: the current position becomes the home position",
     static_cast<Signals>(Signal::step_output), mode_phases::manual, 2, Coordinate::here, FinalMove::if_enabled,
     false, false, true},
    {HomingMode::switch_release, "switch_release", "seek the switch, back off; the release edge is the reference",
     Signal::step_output | Signal::home_sensor, mode_phases::release, 7, Coordinate::reference_edge,
     FinalMove::if_enabled, true, true, true},
    {HomingMode::switch_reapproach, "switch_reapproach",
     "as 2, then approach again at latch feedrate; that edge is the reference",
     Signal::step_output | Signal::home_sensor, mode_phases::reapproach, 8, Coordinate::reference_edge,
     FinalMove::if_enabled, true, true, true},
    {HomingMode::switch_index, "switch_index", "release edge, then the next encoder index pulse",
     Signal::step_output | Signal::home_sensor | Signal::index, mode_phases::index, 8, Coordinate::reference_edge,
     FinalMove::if_enabled, true, true, true},
    {HomingMode::absolute, "absolute", "position from the absolute encoder, no movement",
     Signal::step_output | Signal::absolute_encoder, mode_phases::absolute, 1, Coordinate::absolute_encoder,
     FinalMove::never, false, false, true},
    {HomingMode::absolute_final, "absolute_final", "absolute, then move to final_position",
     Signal::step_output | Signal::absolute_encoder, mode_phases::manual, 2, Coordinate::absolute_encoder,
     FinalMove::always, false, false, true},
    {HomingMode::pushing_release, "pushing_release", "seek, push into the mechanical stop, release edge",
     Signal::step_output | Signal::home_sensor | Signal::push_output, mode_phases::push_release, 8,
     Coordinate::reference_edge, FinalMove::if_enabled, false, true, true},
    {HomingMode::pushing_reapproach, "pushing_reapproach", "seek, push into the mechanical stop, re-approach edge",
     Signal::step_output | Signal::home_sensor | Signal::push_output, mode_phases::push_reapproach, 9,
     Coordinate::reference_edge, FinalMove::if_enabled, false, true, true},
    {HomingMode::hard_stop, "hard_stop",
     "no switch: push into the mechanical stop at latch feedrate and reduced current until the drive reports a "
     "stall; the stop is the reference",
     Signal::step_output | Signal::push_output, mode_phases::hard_stop, 5,
     Coordinate::mechanical_stop, FinalMove::if_enabled, false, false, false,
     // The stop: the drive's stall input, or the encoder falling behind the steps.
     {static_cast<Signals>(Signal::stall), static_cast<Signals>(Signal::absolute_encoder)}},
    // The drive homes itself on its own sensor at its own speeds (CiA 402
    // homing mode, HOME/HOME-END of Oriental AZ and IAI drives): the module
    // sends no steps meanwhile, so it can square no gantry. Its home input is
    // free, so it may serve as a hard limit, as with manual.
    {HomingMode::drive, "drive", "the drive homes itself on request; home_position where it reports done",
     Signal::step_output | Signal::drive_request | Signal::drive_done, mode_phases::drive, 3,
     Coordinate::drive_reference, FinalMove::if_enabled, false, false, true},
    // A home cam in mid-travel between two limit switches (CiA 402 methods
    // 7-14 and 23-30, Beckhoff MC_StepLimitSwitch): the search reverses at
    // the limit switch it meets first. limit_reversal runs only when it does.
    // The cam is not at an end of travel, so it cannot be a hard limit; the
    // limit switches are. No gantry: one side reversing alone would rack it.
    {HomingMode::home_cam, "home_cam",
     "seek the home cam, reversing at the limit switch if met first; the configured edge of the cam "
     "(cam_edge) is the reference",
     Signal::step_output | Signal::home_sensor | Signal::limit_min | Signal::limit_max, mode_phases::home_cam, 7,
     Coordinate::reference_edge, FinalMove::if_enabled, false, false, false},
    // clang-format on
};
inline constexpr std::uint8_t kHomingModeCount = std::size(kModeTable);
static_assert(lists_every_value(kModeTable, HomingMode::home_cam));
constexpr std::span<const ModeRow> enum_table(HomingMode) { return kModeTable; }

// Each row's phase count matches its list, and every method that moves to
// find an edge starts with the pre-move and ends on assign (and the final move).
constexpr bool rows_are_consistent() {
  for (const ModeRow& r : kModeTable) {
    for (std::size_t i = 0; i < kMaxModePhases; ++i)
      if ((i < r.phase_count) != (r.phases[i] != Phase::idle)) return false;
    if (r.coordinate == Coordinate::none && r.phase_count != 0) return false;
    if (r.coordinate != Coordinate::none && !r.runs(Phase::assign)) return false;
    if (r.runs(Phase::final_move) != (r.final_move != FinalMove::never)) return false;
    if (r.coordinate == Coordinate::reference_edge &&
        !(r.needs_signal(Signal::home_sensor) && (r.runs(Phase::seek) || r.runs(Phase::cam_seek)) &&
          r.runs(Phase::pull_off)))
      return false;
    if (r.runs(Phase::index) != r.needs_signal(Signal::index)) return false;
    if (r.runs(Phase::push) && !r.needs_signal(Signal::push_output)) return false;
    // A method that pushes to a stop finds it by one signal per choice, the
    // stall input by default; no other method has the choice.
    if (r.runs(Phase::push_to_stop) != r.detects_stop()) return false;
    for (const Signals s : r.stop_signals)
      if ((s == 0) == r.detects_stop()) return false;
    if (r.detects_stop() && r.stop_signals[static_cast<std::size_t>(StallDetect::stall_input)] !=
                                static_cast<Signals>(Signal::stall))
      return false;
    if ((r.coordinate == Coordinate::mechanical_stop) != r.runs(Phase::push_to_stop)) return false;
    if ((r.gantry_master || r.gantry_slave) && !r.needs_signal(Signal::home_sensor)) return false;
    if (r.runs(Phase::drive_homing) != r.needs_signal(Signal::drive_request)) return false;
    if (r.needs_signal(Signal::drive_request) != r.needs_signal(Signal::drive_done)) return false;
    if ((r.coordinate == Coordinate::drive_reference) != r.runs(Phase::drive_homing)) return false;
    // A search that reverses at the limit switches needs both of them.
    if (r.runs(Phase::limit_reversal) !=
        (r.needs_signal(Signal::limit_min) && r.needs_signal(Signal::limit_max)))
      return false;
  }
  return true;
}
static_assert(rows_are_consistent());

// The row of a mode; a number outside the table (an old or corrupt register
// value) reads as disabled, which the register validation refuses anyway.
constexpr const ModeRow& mode_row(HomingMode m) {
  const auto i = static_cast<std::size_t>(m);
  return i < std::size(kModeTable) ? kModeTable[i] : kModeTable[0];
}

std::string_view mode_name(HomingMode mode);

// Named questions over a mode's row, for code that asks one of them.
constexpr bool mode_uses_switch(HomingMode m) { return mode_row(m).needs_signal(Signal::home_sensor); }
constexpr bool mode_is_pushing(HomingMode m) { return mode_row(m).runs(Phase::push); }
constexpr bool mode_reapproaches(HomingMode m) { return mode_row(m).runs(Phase::reapproach); }
constexpr bool mode_is_absolute(HomingMode m) { return mode_row(m).coordinate == Coordinate::absolute_encoder; }
// The mode gives the axis a coordinate (disabled does not home).
constexpr bool mode_homes(HomingMode m) { return mode_row(m).coordinate != Coordinate::none; }

}  // namespace homing
