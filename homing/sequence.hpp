#pragma once
// Which axes a homing cycle moves, step by step. The engine runs this plan;
// the tools estimate a cycle from the same plan.
#include <array>

#include "axes.hpp"
#include "settings.hpp"

namespace homing {

struct CyclePlan {
  // Axes homed together in each step. Slaves go with their master whatever
  // their own bit says; homing one axis of a gantry homes its partner too;
  // an axis is homed in the first step that names it.
  std::array<AxisMask, 6> steps{};
  // Home-all only: axes in no step that are given their coordinate where
  // they stand once the steps are done (a slave with its master).
  AxisMask unsequenced = 0;
  AxisMask covered() const;
};

// `all`: home-all along global.sequence_steps. Else the axes `requested`
// (cmd.home.<a>, cmd.home_axes) with their gantry partners, in one cycle: in
// the order of the sequence steps that name them (numbered from 1, no empty
// steps), then those in no step together, homed by their mode.
CyclePlan plan_cycle(const Settings& settings, AxisMask requested, bool all);

}  // namespace homing
