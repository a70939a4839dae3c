// Each axis's output channel: the motion of the motor it drives now (a
// commutator master's channel drives its slave's motor while it aligns),
// the enable, push, commutator, drive home-request and indexer unlock outputs.
#include "engine.hpp"
#include "gantry.hpp"

namespace homing {

// An output channel's position is continuous: when the commutator hands the
// master's output to the slave motor (and back), the channel goes on from
// where it was, so a pulse generator never sees a jump.
void Engine::route_outputs(const Settings& settings) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisRun& run = axes_[a];
    AxisOutputs& out = outputs_.axes[a];
    std::size_t source = a;
    if (run.commutator_output)
      if (const int sl = gantry_slave(settings, a); sl >= 0) source = static_cast<std::size_t>(sl);
    OutputChannel& channel = out_channels_[a];
    if (source != channel.source) {
      const double channel_mm = axes_[channel.source].motor.position_mm + channel.offset_mm;
      channel.offset_mm = channel_mm - axes_[source].motor.position_mm;
      channel.source = source;
    }
    const AxisRun& src = axes_[source];
    out.motion = src.command;
    if (out.motion.has_limit) out.motion.limit_mm += channel.offset_mm;
    out.motor = src.motor;
    out.motor.position_mm += channel.offset_mm;
    out.enable = !estop_;
    out.push_output = run.push_output;
    out.commutator_output = run.commutator_output;
    // On exactly while the drive homes in a running cycle: an alarm, abort or
    // e-stop drops it in the same period.
    // A locking indexer not yet unlocked holds it back, as it holds steps.
    out.drive_request = run.phase == Phase::drive_homing && run.in_cycle && !estop_ && run.indexer.lets_move();
    out.indexer_unlock = run.indexer.unlock_output();
  }
}

}  // namespace homing
