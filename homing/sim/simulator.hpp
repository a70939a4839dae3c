#pragma once
// The simulated machine, the default backend. Pure and deterministic: no
// clocks, threads or I/O; every random draw comes from generators seeded from
// the config, so a run repeats exactly. Runs in lock-step with the engine:
//   inputs = sim.inputs(); outputs = engine.step(settings, inputs, dt);
//   sim.advance(outputs, dt);
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "bounce.hpp"
#include "carriage.hpp"
#include "config.hpp"
#include "edge_ring.hpp"
#include "home_sensor.hpp"
#include "homing_drive.hpp"
#include "homing/io.hpp"

namespace homing::sim {

class Simulator {
 public:
  explicit Simulator(const MachineConfig& config);

  // Inputs describing the period the last advance() simulated: levels at its
  // end, edges with times in [0, dt] from its start. Before any advance():
  // the levels at rest, no edges. commands, communication_lost and
  // settings_lost are never touched (the runtime owns them).
  const Inputs& inputs() const { return inputs_; }

  // Runs the step outputs for dt_s: output i plays outputs.axes[i].motion
  // starting from outputs.axes[i].motor (the engine's motor state now) and
  // moves the carriages wired to it (see driving_output).
  void advance(const Outputs& outputs, double dt_s);

  // External-commutator wiring (MachineConfig::commutator_slave[m] = s): one
  // step output, m's. While outputs.axes[m].commutator_output is off it moves
  // carriages m and s alike (each within its own stops, each stopped by its
  // own drive fault); while it is on it moves carriage s only and carriage m
  // stays. outputs.axes[s].motion and .motor are ignored. The master's home
  // input shows the slave's switch while the commutator is on.
  // The step output that drives a carriage: its own, or its commutator master's.
  std::size_t driving_output(std::size_t axis) const;
  // The carriage moved at the end of the last period, or the outputs about to
  // be run would move it (its output runs and is connected to it).
  bool in_motion(std::size_t axis, const Outputs& next) const;

  // How long the machine stays as it is when left running outputs
  // (MachineIo::quiet_for_s): 0 when a carriage moves or would move, or a
  // drive homes or has a request to answer; else the time to the next
  // bounce toggle or indexer pin move; infinity when nothing is scheduled.
  double quiet_for_s(const Outputs& outputs) const;

  // Knobs at run time (as Modbus writes them). set_axis_config keeps the
  // carriage where it is (its actual_position_mm is ignored: use place()).
  void set_axis_config(std::size_t axis, const AxisConfig& config);
  // actual_position_mm here is the live carriage position.
  const AxisConfig& axis_config(std::size_t axis) const { return config_.axes[axis]; }
  // Refused (false) while the axis moves. Clamped to the mechanical stops.
  bool place(std::size_t axis, double actual_mm);
  // Shifts the carriage by mm without the controller knowing (within the stops).
  void lose_steps(std::size_t axis, double mm);
  // Wires axis slave (-1: none) to master's step output through a commutator.
  // Takes effect at the next advance(); the carriages stay where they are.
  void set_commutator_slave(std::size_t master, int slave);
  // Fits (or removes) a locking indexer on the axis; a fitted one starts locked.
  void set_indexer(std::size_t axis, bool fitted);
  void set_estop(bool pressed);
  void set_start_button(bool pressed);
  void set_homing_permit(bool on);
  // Restarts every generator from this seed and redraws the pending edge noise.
  void set_seed(std::uint64_t seed);

  double actual_position_mm(std::size_t axis) const { return axes_[axis].actual_mm; }
  // The physical switch: no fault, polarity or bounce.
  bool sensor_active(std::size_t axis) const { return axes_[axis].sensor.active(); }
  bool at_hard_stop(std::size_t axis) const;
  // The physical limit switch at the negative (max_end false) or positive end
  // is active: carriage at or beyond it, or forced by a limits fault.
  bool limit_active(std::size_t axis, bool max_end) const;
  // The output driving this carriage is still running at the end of the last
  // period and is connected to it (a drive fault does not count: the motor runs),
  // or a drive homing itself moved it in the last period.
  bool moving(std::size_t axis) const { return axes_[axis].moving; }
  // Drive mode: the drive reports home done / runs its own homing now.
  bool drive_done(std::size_t axis) const { return axes_[axis].drive.done(config_.axes[axis]); }
  bool drive_homing(std::size_t axis) const { return axes_[axis].drive.homing(); }
  // Locking indexer: its pin is in and holds the carriage.
  bool indexer_locked(std::size_t axis) const { return axes_[axis].pin_in; }
  // During the last period the motor driving this carriage ran while its
  // indexer held it (the steps were lost): what must never happen.
  bool moved_while_locked(std::size_t axis) const { return axes_[axis].moved_while_locked; }
  double time_s() const { return time_s_; }
  const MachineConfig& config() const { return config_; }

  // True sensor edges (bounce excluded), oldest first; the last
  // EdgeRing::kCapacity per axis are kept.
  std::size_t edges(std::size_t axis, std::span<EdgeRecord> out) const;
  std::vector<EdgeRecord> edges(std::size_t axis) const;
  std::optional<EdgeRecord> last_edge(std::size_t axis) const;
  std::optional<EdgeRecord> last_edge(std::size_t axis, bool to_active) const;
  // Edges since construction, including those no longer kept.
  std::uint64_t edge_count(std::size_t axis) const { return axes_[axis].ring.total(); }

 private:
  struct Axis {
    double actual_mm = 0;
    bool moving = false;
    HomeSensor sensor{};
    BounceQueue bounce{};
    bool bounce_odd = false;       // an odd number of bounce toggles so far: contact is flipped
    bool reported_level = false;   // electrical level at the end of the last period
    EdgeRing ring{};
    double held_since_s = -1;      // the motor has driven into a stop since then (-1: not)
    double stall_after_s = 0;      // this contact's detection time
    std::uint64_t contacts = 0;    // contacts with a stop so far (draws the detection time)
    std::uint64_t encoder_reads = 0;  // noisy encoder readings so far (draws their noise)
    HomingDrive drive{};           // drive mode: the drive's own homing
    bool pin_in = false;           // locking indexer: the pin holds the carriage
    double pin_timer_s = 0;        // how long the unlock output has wanted the pin to move
    bool moved_while_locked = false;
  };
  bool out_request(std::size_t axis, std::size_t output, const AxisOutputs& out) const;

  void reseed();
  // The commutator slave wired to master's output, or -1.
  int wired_slave(std::size_t master) const;
  // Whether output (driving_output(axis)) reaches carriage axis now.
  bool connected(std::size_t axis, std::size_t output, const Outputs& outputs) const;
  void advance_axis(std::size_t axis, std::size_t output, const AxisOutputs& drive, bool linked,
                    double dt_s);
  bool electrical_level(std::size_t axis) const;
  // The drive's stall output at the end of a period whose carriage path ended
  // at end_mm, the motor moving from motor_start_mm to motor_end_mm.
  bool stall_output(std::size_t axis, const CarriagePath& path, double motor_start_mm, double motor_end_mm);
  bool reports_edges(std::size_t axis) const;
  // What the encoder reads now (absolute_position_mm).
  double encoder_reading(std::size_t axis);
  void route_sensors(const Outputs& outputs);
  void set_limit_levels(std::size_t axis);
  void advance_indexer(std::size_t axis, bool unlock_output, double dt_s);

  MachineConfig config_;
  std::array<Axis, kAxisCount> axes_{};
  std::array<AxisInputs, kAxisCount> own_{};  // each axis's own sensor channel before routing
  Inputs inputs_{};
  double time_s_ = 0;
};

}  // namespace homing::sim
