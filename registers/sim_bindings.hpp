#pragma once
// The simulator unit (--sim-unit, default 247): its rows bound to
// homing::sim::MachineConfig and to what the simulator shows. Kept apart from
// the module codec so the module side never depends on the simulator.
#include <array>
#include <cstdint>
#include <expected>
#include <span>
#include <vector>

#include "homing/sim/config.hpp"
#include "registers/codec.hpp"
#include "registers/validate.hpp"

namespace registers {

// sim.estop and sim.start_button (coils).
struct SimSwitches {
  bool estop = false;
  bool start_button = false;
};

// What the running simulator shows, sampled by the runtime for a read.
struct SimReadback {
  std::array<double, homing::kAxisCount> actual_position_mm{};  // Simulator::actual_position_mm
  std::array<bool, homing::kAxisCount> sensor{};                // Simulator::sensor_active
  std::array<bool, homing::kAxisCount> at_hard_stop{};          // Simulator::at_hard_stop
  std::array<std::uint8_t, homing::kAxisCount> driven_by{};     // 0 own output, m + 1: Simulator::driving_output
  std::array<bool, homing::kAxisCount> indexer_locked{};        // Simulator::indexer_locked
  std::array<bool, homing::kAxisCount> limit_min{};             // Simulator::limit_active(a, false)
  std::array<bool, homing::kAxisCount> limit_max{};             // Simulator::limit_active(a, true)
};

// The table's defaults for the simulated machine (a home-all with
// default_settings() succeeds on it).
homing::sim::MachineConfig default_sim_config();
SimSwitches default_sim_switches();

// Raw value of any simulator-unit register. sim.<a>.lose_steps reads 0.
std::int64_t sim_raw(const Register& reg, const homing::sim::MachineConfig& config, const SimSwitches& switches,
                     const SimReadback& readback);

struct AcceptedSimWrite {
  std::vector<Change> changes;
  homing::sim::MachineConfig config;  // with the request applied (call Simulator::set_axis_config)
  SimSwitches switches;
  std::array<bool, homing::kAxisCount> axes_written{};     // a sim.<a>.* register of that axis is written
  std::array<bool, homing::kAxisCount> placed{};           // actual_position written: Simulator::place
  std::array<double, homing::kAxisCount> lose_steps_mm{};  // Simulator::lose_steps, 0 = none
  bool seed_written = false;                               // Simulator::set_seed(config.seed)
};

// Writes that move a carriage or what it meets (the carriage itself, its cams,
// stops, index pulses, the encoder's zero, the drive's home): refused with 06
// while that carriage moves, since nothing real jumps under a moving axis.
// Everything else (faults, noise, bounce, wiring, lost steps, delays) may be
// written at any moment, to pull a wire or fault a drive mid-cycle.
bool moves_geometry(Key key);

// A write to the simulator unit, all or nothing, like validate_write, against
// the configuration it will be applied to (the runtime calls it on the live
// simulator, so two writes in a row never undo each other). Not decided here:
// exception 06 when a write changes a register that moves_geometry while that
// carriage moves (the runtime asks Simulator::in_motion for each such change).
std::expected<AcceptedSimWrite, Refusal> validate_sim_write(Table table, std::uint16_t start,
                                                            std::span<const std::uint16_t> values,
                                                            WordOrder order,
                                                            const homing::sim::MachineConfig& config,
                                                            const SimSwitches& switches,
                                                            const SimReadback& readback);

}  // namespace registers
