#include "sequence.hpp"

#include "gantry.hpp"

namespace homing {

AxisMask CyclePlan::covered() const {
  AxisMask out = 0;
  for (AxisMask m : steps) out |= m;
  return out;
}

namespace {

// The home-all plan cut down to the named axes: the steps that name some of
// them, in order and without gaps, then those in no step, together.
CyclePlan named_axes(const CyclePlan& all, AxisMask named) {
  CyclePlan plan;
  std::size_t n = 0;
  AxisMask covered = 0;
  for (AxisMask step : all.steps) {
    if (!(step & named)) continue;
    plan.steps[n++] = step & named;
    covered |= step & named;
  }
  // Steps are disjoint and not empty: with the rest there are at most six.
  if (const AxisMask rest = named & static_cast<AxisMask>(~covered)) plan.steps[n] = rest;
  return plan;
}

}  // namespace

CyclePlan plan_cycle(const Settings& settings, AxisMask requested, bool all) {
  CyclePlan plan;
  auto with_partners = [&](AxisMask mask, bool in_sequence) {
    AxisMask out = 0;
    for (std::size_t a = 0; a < kAxisCount; ++a) {
      if (!(mask & axis_bit(a))) continue;
      const int m = master_of(settings.axes[a]);
      const std::size_t master = m >= 0 ? static_cast<std::size_t>(m) : a;
      if (m >= 0 && in_sequence) continue;  // in a sequence, a slave's own bit is ignored
      out |= axis_bit(master);
      const int s = gantry_slave(settings, master);
      if (s >= 0) out |= axis_bit(static_cast<std::size_t>(s));
    }
    return out;
  };
  AxisMask covered = 0;
  for (std::size_t i = 0; i < plan.steps.size(); ++i) {
    plan.steps[i] = with_partners(settings.global.sequence_steps[i], true) & static_cast<AxisMask>(~covered);
    covered |= plan.steps[i];
  }
  if (!all) return named_axes(plan, with_partners(requested, false));
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (!(covered & axis_bit(a)) && master_of(settings.axes[a]) < 0 && mode_homes(settings.axes[a].mode))
      plan.unsequenced |= axis_bit(a);
  // A slave is assigned with its master, whatever its own mode.
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const int m = gantry_master(settings, a);
    if (m >= 0 && (plan.unsequenced & axis_bit(static_cast<std::size_t>(m)))) plan.unsequenced |= axis_bit(a);
  }
  return plan;
}

}  // namespace homing
