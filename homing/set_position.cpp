// Service: set an unhomed axis's coordinate where it stands, without moving
// (a technician who lined a carriage up on a mark, or an axis that never
// homes). The axis stays unhomed: the coordinate is the technician's word,
// not a reference the module found, so what needs a homed axis still waits.
#include <cmath>

#include "engine.hpp"
#include "gantry.hpp"

namespace homing {

void Engine::set_position_commands(const Settings& settings, const Commands& c) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(c.set_position_axes & axis_bit(a))) continue;
    ++command_count_;
    const double target = c.set_position_mm[a];
    const int slave = gantry_slave(settings, a);
    AxisRun& run = axes_[a];
    AxisRun* partner = slave >= 0 ? &axes_[static_cast<std::size_t>(slave)] : nullptr;
    CommandResult r = CommandResult::accepted;
    if (!std::isfinite(target)) r = CommandResult::refused_invalid;
    // A pair has one coordinate: it is set through the master.
    else if (gantry_master(settings, a) >= 0) r = CommandResult::refused_slave_axis;
    // A reference found by homing is never overwritten by hand.
    else if (run.homed() || (partner && partner->homed())) r = CommandResult::refused_homed;
    // Under a cycle or a motion the coordinate is what the phases count on.
    else if (cycle_active_ || run.busy() || (partner && partner->busy())) r = CommandResult::refused_busy;
    last_result_ = r;
    if (r != CommandResult::accepted) continue;
    run.offset_mm = target - run.motor.position_mm;
    ++run.positions_set;
    if (partner) partner->offset_mm = target - partner->motor.position_mm;
  }
}

}  // namespace homing
