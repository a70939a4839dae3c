#pragma once
// The rules the campaign holds the engine to, written once: what an axis homes
// with (a slave: its master's motion settings, its own sensor settings), which
// axes a cycle covers, in which step, and which may move.
#include <array>
#include <cstddef>
#include <optional>

#include "homing/gantry.hpp"
#include "homing/settings.hpp"
#include "homing/settings_check.hpp"

namespace campaign {

using namespace homing;

// -1 when the axis is not a slave (or names no axis), else its master.
inline int master_index(const Settings& s, std::size_t a) {
  const int m = master_of(s.axes[a]);
  return m >= 0 && m < static_cast<int>(kAxisCount) && m != static_cast<int>(a) ? m : -1;
}

// The slave of master m, or -1.
inline int slave_index(const Settings& s, std::size_t m) {
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (master_index(s, a) == static_cast<int>(m)) return static_cast<int>(a);
  return -1;
}

inline int partner_index(const Settings& s, std::size_t a) {
  const int m = master_index(s, a);
  return m >= 0 ? m : slave_index(s, a);
}

// The settings an axis homes, jogs and moves with: the engine's one
// definition (homing/gantry.hpp, documented in README "what a slave
// inherits"): a slave of a valid pair takes its master's motion settings and
// keeps its own sensor settings, pull-off (software-slaved only: a commutator
// pair pulls off together on one output), compensation, misalignment and
// shared limit; the pair moves with the lower acceleration.
inline AxisSettings effective(const Settings& s, std::size_t a) { return motion_settings(s).axes[a]; }

using homing::final_move_wanted;

inline double dir_of(const AxisSettings& e) { return e.direction == Direction::positive ? 1.0 : -1.0; }

// Fields a slave takes from its master: its own values there must be ignored.
inline bool inherited_field(AxisField f) {
  switch (f) {
    // Not mode: a slave's own mode says whether it has a sensor of its own
    // (a switch or pushing mode; anything else is slave_sensor_missing). The
    // phases it runs follow its master's mode.
    case AxisField::direction:
    case AxisField::seek_feedrate:
    case AxisField::latch_feedrate:
    case AxisField::max_seek_travel:
    case AxisField::max_stop_distance:
    case AxisField::max_backoff:
    case AxisField::home_position:
    case AxisField::final_position:
    case AxisField::final_move_enable:
    case AxisField::pre_move_mode:
    case AxisField::pre_move_distance:
    case AxisField::push_distance:
    case AxisField::index_pitch:
    case AxisField::soft_limit_min:
    case AxisField::soft_limit_max:
    case AxisField::soft_limits_enable:
    case AxisField::jog_feedrate:
      return true;
    default:
      return false;
  }
}

// The engine's whole rule set: the first refusal, if any.
inline std::optional<SettingsFault> first_fault(const Settings& s) {
  for (const auto& f : homing::check_settings(s))
    if (f) return f;
  return std::nullopt;
}

// What one cycle covers.
struct CyclePlan {
  bool all = false;
  AxisMask covered = 0;      // home in a sequence step (with or without motion)
  AxisMask unsequenced = 0;  // assigned at the end of a home-all, without motion
  AxisMask movers = 0;       // may move during the cycle
  std::array<int, kAxisCount> step{};  // 1..6 for covered axes, 0 otherwise
};

inline bool moves_when_homing(const Settings& s, std::size_t a) {
  const AxisSettings e = effective(s, a);
  return mode_uses_switch(e.mode) || final_move_wanted(e);
}

inline CyclePlan plan_cycle(const Settings& s, bool all, AxisMask requested) {
  CyclePlan p;
  p.all = all;
  auto cover = [&](std::size_t a, int step) {
    if (p.covered & axis_bit(a)) return;
    p.covered |= axis_bit(a);
    p.step[a] = step;
  };
  auto cover_with_slave = [&](std::size_t a, int step) {
    cover(a, step);
    const int sl = slave_index(s, a);
    if (sl >= 0) cover(static_cast<std::size_t>(sl), step);
  };
  if (all) {
    for (int i = 0; i < 6; ++i)
      for (std::size_t a = 0; a < kAxisCount; ++a)
        if ((s.global.sequence_steps[static_cast<std::size_t>(i)] & axis_bit(a)) && master_index(s, a) < 0)
          cover_with_slave(a, i + 1);
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      if (p.covered & axis_bit(a)) continue;
      const int m = master_index(s, a);
      if (m < 0 && s.axes[a].mode != HomingMode::disabled) p.unsequenced |= axis_bit(a);
    }
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      const int m = master_index(s, a);
      if (m >= 0 && (p.unsequenced & axis_bit(static_cast<std::size_t>(m)))) p.unsequenced |= axis_bit(a);
    }
  } else {
    // The named axes with their gantry partners, in one cycle: in the order
    // of the sequence steps that name them (numbered from 1, no gaps), then
    // the rest together in one last step.
    AxisMask named = 0;
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      if (!(requested & axis_bit(a))) continue;
      const int m = master_index(s, a);
      const std::size_t root = m >= 0 ? static_cast<std::size_t>(m) : a;
      named |= axis_bit(root);
      if (const int sl = slave_index(s, root); sl >= 0) named |= axis_bit(static_cast<std::size_t>(sl));
    }
    int step = 0;
    for (int i = 0; i < 6; ++i) {
      bool counted = false;
      for (std::size_t a = 0; a < kAxisCount; ++a) {
        if (!(s.global.sequence_steps[static_cast<std::size_t>(i)] & axis_bit(a)) || master_index(s, a) >= 0 ||
            !(named & axis_bit(a)) || (p.covered & axis_bit(a)))
          continue;
        if (!counted) ++step;
        counted = true;
        cover_with_slave(a, step);
      }
    }
    bool rest = false;
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      if (!(named & axis_bit(a)) || (p.covered & axis_bit(a))) continue;
      if (!rest) ++step;
      rest = true;
      cover(a, step);
    }
  }
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((p.covered & axis_bit(a)) && s.axes[a].mode != HomingMode::disabled && moves_when_homing(s, a))
      p.movers |= axis_bit(a);
  return p;
}

}  // namespace campaign
