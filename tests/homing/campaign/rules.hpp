#pragma once
// The rules the campaign holds the engine to, written once: what an axis homes
// with (a slave: its master's motion settings, its own sensor settings), which
// axes a cycle covers, in which step, and which may move.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <optional>

#include "homing/alarms.hpp"
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

// The campaign's own reading of docs/homing-methods.md "Gantries: what a slave inherits",
// written here rather than taken from homing/gantry.hpp so that a wrong rule
// in the engine shows as a failure instead of becoming the expectation.
// A pair is one the rule set takes: the slave names another axis that is no
// slave itself, both home on a sensor (switch or pushing mode), and no
// earlier axis is already that master's slave.
inline int pair_master(const Settings& s, std::size_t a) {
  const int m = master_index(s, a);
  if (m < 0) return -1;
  const AxisSettings& ms = s.axes[static_cast<std::size_t>(m)];
  if (!mode_uses_switch(s.axes[a].mode) || !mode_uses_switch(ms.mode) || master_index(s, static_cast<std::size_t>(m)) >= 0)
    return -1;
  for (std::size_t other = 0; other < a; ++other)
    if (master_index(s, other) == m) return -1;
  return m;
}

// The settings an axis homes, jogs and moves with. A slave takes its
// master's motion settings (the phases of its mode, direction, feedrates,
// max seek travel, max stop distance, max back-off, pre-move, push distance,
// index pitch, home position, final position and move, jog feedrate, soft
// limits) and keeps its own sensor_nc, debounce, shared_limit, pull_off
// (software-slaved only: a commutator pair pulls off together),
// switch_compensation and max_misalignment; both sides of a pair move with
// the lower of the two accelerations.
inline AxisSettings effective(const Settings& s, std::size_t a) {
  const AxisSettings& own = s.axes[a];
  int m = pair_master(s, a);
  if (m < 0) {
    // A master: its own settings, at the pair's acceleration.
    AxisSettings out = own;
    for (std::size_t x = 0; x < kAxisCount; ++x)
      if (pair_master(s, x) == static_cast<int>(a))
        out.acceleration_mm_per_s2 = std::min(own.acceleration_mm_per_s2, s.axes[x].acceleration_mm_per_s2);
    return out;
  }
  const AxisSettings& ms = s.axes[static_cast<std::size_t>(m)];
  AxisSettings out = own;
  out.mode = ms.mode;
  out.direction = ms.direction;
  out.seek_feedrate_mm_per_min = ms.seek_feedrate_mm_per_min;
  out.latch_feedrate_mm_per_min = ms.latch_feedrate_mm_per_min;
  out.max_seek_travel_mm = ms.max_seek_travel_mm;
  out.max_stop_distance_mm = ms.max_stop_distance_mm;
  out.max_backoff_mm = ms.max_backoff_mm;
  out.pre_move_mode = ms.pre_move_mode;
  out.pre_move_distance_mm = ms.pre_move_distance_mm;
  out.push_distance_mm = ms.push_distance_mm;
  out.index_pitch_mm = ms.index_pitch_mm;
  out.home_position_mm = ms.home_position_mm;
  out.final_position_mm = ms.final_position_mm;
  out.final_move_enable = ms.final_move_enable;
  out.jog_feedrate_mm_per_min = ms.jog_feedrate_mm_per_min;
  out.soft_limit_min_mm = ms.soft_limit_min_mm;
  out.soft_limit_max_mm = ms.soft_limit_max_mm;
  out.soft_limits_enable = ms.soft_limits_enable;
  if (own.slave_mode == SlaveMode::external_commutator) out.pull_off_mm = ms.pull_off_mm;
  out.acceleration_mm_per_s2 = std::min(own.acceleration_mm_per_s2, ms.acceleration_mm_per_s2);
  return out;
}

// The mode whose edge a slave squares on: a commutator slave searches its
// own edge alone at latch feedrate (docs/homing-methods.md "Gantries: topologies") and has no
// index input of its own, so an index master's slave squares on its release
// edge; otherwise the mode it homes with.
inline HomingMode squaring_mode(const Settings& s, std::size_t a) {
  const AxisSettings e = effective(s, a);
  if (pair_master(s, a) >= 0 && s.axes[a].slave_mode == SlaveMode::external_commutator && e.mode == HomingMode::switch_index)
    return HomingMode::switch_release;
  return e.mode;
}

using homing::final_move_wanted;

inline double dir_of(const AxisSettings& e) { return e.direction == Direction::positive ? 1.0 : -1.0; }

// A pre-move "always" from x reaches the mechanical stop on its side (the
// far one, away from home): the axis is not homed, so nothing tells the
// engine where that stop is (seeds 193011366, 194020875).
inline bool pre_move_meets_far_stop(const AxisSettings& e, double x, double stop_min_mm, double stop_max_mm) {
  const double far_stop = dir_of(e) > 0 ? stop_min_mm : stop_max_mm;
  return e.pre_move_mode == PreMove::always && std::abs(x - far_stop) < e.pre_move_distance_mm + 0.01;
}

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

// README: a switch or pushing mode searches its sensor's edge, hard-stop
// homing pushes into its mechanical stop; the other modes move only for the
// final move.
inline bool searches(HomingMode m) { return mode_uses_switch(m) || m == HomingMode::hard_stop; }
// The modes that push into a mechanical stop with the push output on.
inline bool pushes_into_stop(HomingMode m) { return mode_is_pushing(m) || m == HomingMode::hard_stop; }

// The failure policy (docs/homing-methods.md "Failure policy"), as the
// campaign reads it. Causes that concern the whole machine stop every axis
// whatever the policy.
inline bool stops_everything(AlarmCode c) {
  return c == AlarmCode::emergency_stop || c == AlarmCode::communication_lost || c == AlarmCode::permit_withdrawn ||
         c == AlarmCode::settings_lost;
}
// return_to_start: an axis with an alarm of its own goes back only after an
// abort or a search that went wrong away from its sensor, never one that ran
// on without it (it may have met its mechanical stop).
inline bool alarm_lets_go_back(AlarmCode c) {
  switch (c) {
    case AlarmCode::none:
    case AlarmCode::aborted:
    case AlarmCode::not_released:
    case AlarmCode::index_not_found:
    case AlarmCode::switch_not_repeatable:
      return true;
    default:
      return false;
  }
}
// The way back runs at the lower of the jog and seek feedrates (mm/s).
inline double return_speed(const AxisSettings& e) {
  const double f = e.jog_feedrate_mm_per_min > 0 && e.seek_feedrate_mm_per_min > 0
                       ? std::min(e.jog_feedrate_mm_per_min, e.seek_feedrate_mm_per_min)
                       : std::max(e.jog_feedrate_mm_per_min, e.seek_feedrate_mm_per_min);
  return f / 60.0;
}

inline bool moves_when_homing(const Settings& s, std::size_t a) {
  const AxisSettings e = effective(s, a);
  // A drive homing itself moves the carriage without steps.
  return searches(e.mode) || e.mode == HomingMode::drive || final_move_wanted(e);
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
