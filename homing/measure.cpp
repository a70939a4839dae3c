// The commissioning measurement (measure.hpp): judged as a single-axis home
// is, then refused for what it cannot measure; accepted, it is a normal
// single-axis homing cycle whose axis goes on to measure_travel instead of
// done (its phase: measure_phases.cpp).
#include "engine.hpp"
#include "gantry.hpp"

namespace homing {

// What refuses a measurement of one axis beyond what refuses homing it alone.
CommandResult Engine::measure_refusal(const Settings& settings, std::size_t axis) const {
  const AxisSettings& s = settings.axes[axis];
  if (s.mode == HomingMode::disabled) return CommandResult::refused_invalid;
  // One side alone would rack a pair over its whole travel.
  if (gantry_partner(settings, axis) >= 0 || master_of(s) >= 0) return CommandResult::refused_gantry_pair;
  if (travel_end(s) == TravelEnd::none) return CommandResult::refused_no_travel_end;
  if (axes_[axis].limit_tripped) return CommandResult::refused_hard_limit;
  return CommandResult::accepted;
}

// One axis per command: the figures belong to one axis, and the travel is
// the longest a machine makes. Any refusal moves nothing.
void Engine::measure_command(const Settings& settings, AxisMask axes) {
  axes &= kAllAxes;
  ++command_count_;
  int axis = -1;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (axes & axis_bit(a)) axis = axis < 0 ? static_cast<int>(a) : static_cast<int>(kAxisCount);
  if (axis < 0 || axis >= static_cast<int>(kAxisCount)) {
    last_result_ = CommandResult::refused_invalid;
    return;
  }
  const auto a = static_cast<std::size_t>(axis);
  if (cycle_active_) {
    last_result_ = axes_[a].measuring ? CommandResult::already_running : CommandResult::refused_busy;
    return;
  }
  if (const CommandResult r = homing_refusal(settings); r != CommandResult::accepted) {
    last_result_ = r;
    return;
  }
  // A machine that homes all axes together or none homes none alone for a measurement either.
  if (!settings.global.single_axis_homing) {
    last_result_ = CommandResult::refused_home_all_only;
    return;
  }
  if (const CommandResult r = measure_refusal(settings, a); r != CommandResult::accepted) {
    last_result_ = r;
    return;
  }
  axes_[a].measurement = {};
  start_cycle(settings, axes, false, axes);
}

}  // namespace homing
