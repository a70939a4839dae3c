// Service: unhome axes on request (a technician who moved a carriage by hand,
// or who wants the next home-all to assign an unsequenced axis afresh). A
// gantry pair also forgets where it was square: squared by hand, it would
// otherwise count its racking from a square that no longer holds.
#include "engine.hpp"
#include "gantry.hpp"

namespace homing {

void Engine::unhome_command(const Settings& settings, AxisMask axes) {
  ++command_count_;
  axes &= kAllAxes;
  // A pair shares one reference: forgetting one side forgets both.
  AxisMask with_partners = axes;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(axes & axis_bit(a))) continue;
    if (const int m = gantry_master(settings, a); m >= 0) with_partners |= axis_bit(static_cast<std::size_t>(m));
    if (const int s = gantry_slave(settings, a); s >= 0) with_partners |= axis_bit(static_cast<std::size_t>(s));
  }
  // Never under a running cycle or a moving axis: its phases and checks count on the reference.
  bool moving = cycle_active_;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((with_partners & axis_bit(a)) && axes_[a].busy()) moving = true;
  if (moving) {
    last_result_ = CommandResult::refused_busy;
    return;
  }
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (with_partners & axis_bit(a)) {
      axes_[a].lose_reference();
      axes_[a].pair_square_mm.reset();
    }
  last_result_ = CommandResult::accepted;
}

}  // namespace homing
