#include "simulator_controls.hpp"

#include "homing/gantry.hpp"
#include "simulator.hpp"

namespace homing::sim {

std::array<int, kAxisCount> commutator_wiring(const Settings& settings) {
  std::array<int, kAxisCount> slave_of_master;
  slave_of_master.fill(-1);
  for (std::size_t s = 0; s < kAxisCount; ++s)
    if (is_commutator_slave(settings, s))
      slave_of_master[static_cast<std::size_t>(gantry_master(settings, s))] = static_cast<int>(s);
  return slave_of_master;
}

SimulatorView SimulatorControls::view() const {
  SimulatorView v;
  v.config = sim_.config();
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisView& axis = v.axes[a];
    axis.actual_position_mm = sim_.actual_position_mm(a);
    axis.sensor = sim_.sensor_active(a);
    axis.at_hard_stop = sim_.at_hard_stop(a);
    axis.moving = sim_.moving(a);
    const std::size_t o = sim_.driving_output(a);
    axis.driven_by = o == a ? 0 : static_cast<std::uint8_t>(o + 1);
    axis.indexer_locked = sim_.indexer_locked(a);
    axis.limit_min = sim_.limit_active(a, false);
    axis.limit_max = sim_.limit_active(a, true);
  }
  v.estop = sim_.inputs().estop;
  v.start_button = sim_.inputs().start_button;
  v.time_s = sim_.time_s();
  return v;
}

void SimulatorControls::follow_settings(const Settings& settings) {
  const std::array<int, kAxisCount> wiring = commutator_wiring(settings);
  for (std::size_t m = 0; m < kAxisCount; ++m)
    if (sim_.config().commutator_slave[m] != wiring[m]) sim_.set_commutator_slave(m, wiring[m]);
  for (std::size_t a = 0; a < kAxisCount; ++a) sim_.set_indexer(a, settings.axes[a].indexer_lock);
}

bool SimulatorControls::in_motion(std::size_t axis, const Outputs& next) const { return sim_.in_motion(axis, next); }
void SimulatorControls::set_axis_config(std::size_t axis, const AxisConfig& config) {
  sim_.set_axis_config(axis, config);
}
bool SimulatorControls::place(std::size_t axis, double actual_mm) { return sim_.place(axis, actual_mm); }
void SimulatorControls::lose_steps(std::size_t axis, double mm) { sim_.lose_steps(axis, mm); }
void SimulatorControls::set_seed(std::uint64_t seed) { sim_.set_seed(seed); }
void SimulatorControls::set_estop(bool pressed) { sim_.set_estop(pressed); }
void SimulatorControls::set_start_button(bool pressed) { sim_.set_start_button(pressed); }

}  // namespace homing::sim
