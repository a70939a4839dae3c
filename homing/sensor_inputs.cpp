// This period's inputs: each home input debounced, its accepted edge placed
// at the motor position of its first transition, and the index pulses.
#include <algorithm>

#include "engine.hpp"
#include "gantry.hpp"

namespace homing {

// The input channel an axis reads its home sensor from: a commutator slave's
// sensor is diverted onto its master's input.
int Engine::sensor_channel(const Settings& settings, std::size_t axis) const {
  if (is_commutator_slave(settings, axis)) return gantry_master(settings, axis);
  return static_cast<int>(axis);
}

// The axis whose motor moves the carriage seen on an input channel.
int Engine::channel_owner(const Settings& settings, std::size_t channel) const {
  if (axes_[channel].commutator_output) {
    const int s = gantry_slave(settings, channel);
    if (s >= 0) return s;
  }
  return static_cast<int>(channel);
}

void Engine::read_inputs(const Settings& settings, const Inputs& inputs, double dt_s) {
  const double period_start_s = time_s_ - dt_s;
  for (std::size_t c = 0; c < kAxisCount; ++c) {
    const AxisInputs& in = inputs.axes[c];
    InputChannel& channel = inputs_[c];
    SensorEvent& ev = channel.event;
    ev = SensorEvent{};
    const std::size_t owner_axis = static_cast<std::size_t>(channel_owner(settings, c));
    const AxisRun& owner = axes_[owner_axis];
    // With the commutator on, the master's input carries the slave's switch.
    const bool nc = settings.axes[owner_axis].sensor_nc;
    Debouncer& filter = channel.filter;
    if (first_step_ || channel.reset) {
      // A new source on this input (start-up, commutator switched): take its
      // level as it is, without inventing an edge.
      filter.reset(in.sensor_level, time_s_);
      channel.reset = false;
    } else {
      auto position_at_offset = [&](double tau) {
        return position_at(owner.period_start, owner.last_command, std::clamp(tau, 0.0, dt_s));
      };
      for (std::uint8_t i = 0; i < in.sensor_edges.count; ++i) {
        const double tau = in.sensor_edges.time_s[i];
        filter.transition(period_start_s + tau, position_at_offset(tau));
      }
      // No timestamps, or more edges than reported: the level still wins,
      // placed in the middle of the period.
      if (filter.raw() != in.sensor_level) filter.transition(period_start_s + dt_s / 2, position_at_offset(dt_s / 2));
      AcceptedEdge edge;
      if (filter.settle(time_s_, settings.axes[owner_axis].debounce_ms / 1000.0, edge)) {
        ev.edge = true;
        ev.accepted = edge;
        ev.accepted.to_level = edge.to_level != nc;  // now means "to active"
      }
      if (in.index_edges.count > 0) {
        ev.index = true;
        ev.index_mm = position_at_offset(in.index_edges.time_s[0]);
      }
    }
    channel.sensor_active = filter.stable() != nc;
    // Limit switches belong to the carriage of the axis, whatever the commutator routes.
    const AxisSettings& own = settings.axes[c];
    axes_[c].readings =
        AxisReadings{in.drive_fault, in.absolute_valid, in.absolute_position_mm, in.stall, in.drive_done,
                     own.limits_fitted && in.limit_min_level != own.limits_nc,
                     own.limits_fitted && in.limit_max_level != own.limits_nc};
  }
}

}  // namespace homing
