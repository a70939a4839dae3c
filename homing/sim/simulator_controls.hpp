#pragma once
// What the simulator unit (homingd --sim-unit) may do to the simulated machine
// beyond what a real one allows: see where each carriage really is, change the
// knobs, place a carriage, press the e-stop. A capability of the simulator
// backend, reached through MachineIo::simulator_controls(); the runtime calls
// it from its control loop only, between two periods. Advancing the machine is
// not part of it: that stays with MachineIo.
#include <array>
#include <cstddef>
#include <cstdint>

#include "config.hpp"
#include "homing/io.hpp"
#include "homing/settings.hpp"

namespace homing::sim {

class Simulator;

// What the simulator shows of one carriage.
struct AxisView {
  double actual_position_mm = 0;
  bool sensor = false;         // the physical switch (no fault, polarity or bounce)
  bool at_hard_stop = false;
  bool moving = false;         // Simulator::moving
  std::uint8_t driven_by = 0;  // 0 its own output, m + 1: master m's (external commutator)
  bool indexer_locked = false; // a fitted locking indexer's pin is in (holds the carriage)
  bool limit_min = false;      // the limit switch at the negative end is active (physical, with faults)
  bool limit_max = false;
};

// The whole simulated machine at one instant, copied out for a reader.
struct SimulatorView {
  MachineConfig config{};  // the live knobs; axes[a].actual_position_mm is where carriage a is
  std::array<AxisView, kAxisCount> axes{};
  bool estop = false;
  bool start_button = false;
  double time_s = 0;  // simulated time since start
};

// The commutator wiring the settings describe (MachineConfig::commutator_slave):
// master m's output drives slave s when the engine takes s for an
// external-commutator slave of m (homing::is_commutator_slave): a pair the
// engine does not run as a gantry (a disabled slave, a second slave of one
// master) is not wired, so no carriage follows a master the engine ignores.
std::array<int, kAxisCount> commutator_wiring(const Settings& settings);

class SimulatorControls {
 public:
  explicit SimulatorControls(Simulator& sim) : sim_(sim) {}
  SimulatorControls(const SimulatorControls&) = delete;
  SimulatorControls& operator=(const SimulatorControls&) = delete;

  SimulatorView view() const;
  // Wires the simulated commutators as the settings say the machine is
  // wired (commutator_wiring) and fits a locking indexer on each axis with
  // axis.<a>.indexer_lock; called whenever the settings change.
  void follow_settings(const Settings& settings);
  // The carriage moves, or the outputs about to run (next) would move it.
  bool in_motion(std::size_t axis, const Outputs& next) const;
  // Keeps the carriage where it is (config.actual_position_mm is ignored: place()).
  void set_axis_config(std::size_t axis, const AxisConfig& config);
  // Refused (false) while the carriage moves; clamped to the mechanical stops.
  bool place(std::size_t axis, double actual_mm);
  // Shifts the carriage by mm without the controller knowing.
  void lose_steps(std::size_t axis, double mm);
  void set_seed(std::uint64_t seed);
  void set_estop(bool pressed);
  void set_start_button(bool pressed);

 private:
  Simulator& sim_;
};

}  // namespace homing::sim
