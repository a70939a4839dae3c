// Gantry pairs while they move: the slave follows its master, the pair
// never racks beyond max_misalignment, and the commutator output goes back
// to the master once the slave motor rests.
#include <algorithm>
#include <cmath>

#include "engine.hpp"
#include "gantry.hpp"
#include "mutation.hpp"

namespace homing {

// A slave is locked to its master except while it homes on its own sensor.
void Engine::follow_masters(const Settings& settings) {
  for (std::size_t s = 0; s < kAxisCount; ++s) {
    const int m = gantry_master(settings, s);  // a refused pair is no pair: nothing follows
    if (m < 0) continue;
    AxisRun& slave = axes_[s];
    const AxisRun& master = axes_[static_cast<std::size_t>(m)];
    const bool independent = slave.in_cycle && !slave.follow_master;
    if (independent) continue;
    MotionCommand cmd = master.command;
    const double delta = slave.motor.position_mm - master.motor.position_mm;
    if (cmd.has_limit) cmd.limit_mm += delta;
    slave.command = cmd;
  }
}

// A gantry never racks beyond its slave's max_misalignment from square,
// stopping distance included, whatever the phase or the cause (a side on its
// sensor, a dead or stuck sensor, a squaring beyond the limit): each period,
// where both sides would come to rest if braked now, or after running this
// period's commands for up to two periods, is compared with where the pair is
// square as the module knows it (pair_square_mm: where it was last assigned
// its home, or where the first cycle found it). Before that could pass the
// limit, the pair is stopped with a misalignment alarm. A pair an earlier
// alarm left racked may so come back to square and up to the limit beyond,
// and a pair found further out than the limit (max_misalignment lowered
// since) may stay as far out on its own side.
void Engine::guard_gantries(const Settings& settings) {
  for (std::size_t sl = 0; sl < kAxisCount; ++sl) {
    const int mi = gantry_master(settings, sl);
    if (mi < 0) continue;
    const std::size_t m = static_cast<std::size_t>(mi);
    AxisRun& slave = axes_[sl];
    const AxisRun& master = axes_[m];
    if (!slave.in_cycle && !master.in_cycle) continue;  // locked together outside a cycle
    const double limit = settings.axes[sl].max_misalignment_mm + (planted(Mutant::racking_allowed_0_2_mm_past_limit) ? 0.2 : 0.0);
    const SquareBand band = square_band(slave.pair_square_mm, slave.pair_rel0_mm, limit);
    auto rest = [&](const AxisRun& run, std::size_t axis, double h) {
      const MotionState at = integrate(run.motor, run.command, h);
      const double v = at.velocity_mm_per_s;
      const double d = stop_distance_mm(std::abs(v), settings.axes[axis].acceleration_mm_per_s2);
      return at.position_mm + (v > 0 ? d : (v < 0 ? -d : 0.0));
    };
    // Two periods ahead: looking as far as a move's braking does (20 ms)
    // would stop square-able pairs at slow accelerations. A period later
    // than that can carry the pair past the limit by what it travels in the
    // extra time (docs/homing-methods.md "Gantries: racking").
    const double horizon = 2 * last_dt_s_;
    // Going back to where the cycle found it (return_to_start), the pair
    // heads for a place it stood in: within the limit of that place is
    // allowed too, or a pair found at its limit could never arrive.
    const bool returning = wind_down_ == WindDown::returning;
    bool out = false;
    double worst = 0;
    for (int k = 0; k <= 4; ++k) {
      const double h = horizon * k / 4;
      const double off_square = band.off_square(rest(slave, sl, h), rest(master, m, h));
      const bool near_start = returning && std::abs(off_square - band.rack_at_start_mm) <= limit;
      if (!band.within(off_square) && !near_start) out = true;
      worst = std::max(worst, std::abs(off_square));
    }
    if (out) {
      Alarm alarm{AlarmCode::misalignment, slave.phase, AxisField::max_misalignment, worst, 0};
      alarm.side = side_at_fault(slave, master);
      alarm.rack_at_start_mm = band.rack_at_start_mm;
      raise(settings, axis_bit(sl), alarm);
      follow_masters(settings);  // the slave brakes with the pair, not on its own old command
    }
  }
}

// The side that carried the pair out: the one still searching while the
// other had found its sensor, else the one moving against the other.
GantrySide Engine::side_at_fault(const AxisRun& slave, const AxisRun& master) {
  const bool slave_found = slave.has_reached(Reached::stopped_on_sensor);
  const bool master_found = master.has_reached(Reached::stopped_on_sensor);
  bool master_side = false;
  if (slave_found != master_found)
    master_side = slave_found;
  else
    master_side = std::abs(master.motor.velocity_mm_per_s) > std::abs(slave.motor.velocity_mm_per_s);
  if (master_side) return master_found ? GantrySide::master_sensor_far : GantrySide::master_no_sensor;
  return slave_found ? GantrySide::slave_sensor_far : GantrySide::slave_no_sensor;
}

// The commutator output goes back to the master once the slave motor it was
// driving is at rest and no longer aligning.
void Engine::release_commutators(const Settings& settings) {
  for (std::size_t m = 0; m < kAxisCount; ++m) {
    AxisRun& master = axes_[m];
    if (!master.commutator_output) continue;
    const int sl = gantry_slave(settings, m);
    const AxisRun* slave = sl >= 0 ? &axes_[static_cast<std::size_t>(sl)] : nullptr;
    const bool busy = slave && slave->aligning && slave->in_cycle;
    const bool moving = slave && slave->motor.velocity_mm_per_s != 0;
    if (busy || moving) continue;
    master.commutator_output = false;
    inputs_[m].reset = true;
  }
}

}  // namespace homing
