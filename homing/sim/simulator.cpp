#include "simulator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "carriage.hpp"
#include "index_pulses.hpp"

namespace homing::sim {
namespace {

constexpr double kTouch_mm = 1e-9;

// Crossed stops (a half-written pair of registers) act as one wall at the minimum.
Stops stops_of(const AxisConfig& c) {
  return Stops{c.hard_stop_min_mm, std::max(c.hard_stop_min_mm, c.hard_stop_max_mm)};
}

// A fraction in [0, 1) from a seed and two counters (splitmix64): the same
// contact draws the same detection time in every run with this seed.
double fraction(std::uint64_t seed, std::uint64_t a, std::uint64_t b) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (a * 1000003ull + b + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

double clamp_to_stops(double x_mm, const AxisConfig& c) {
  const Stops s = stops_of(c);
  return std::clamp(x_mm, s.min_mm, s.max_mm);
}

}  // namespace

Simulator::Simulator(const MachineConfig& config) : config_(config) {
  reseed();
  for (std::size_t i = 0; i < kAxisCount; ++i) {
    AxisConfig& c = config_.axes[i];
    Axis& ax = axes_[i];
    c.actual_position_mm = ax.actual_mm = clamp_to_stops(c.actual_position_mm, c);
    ax.sensor.configure(c);
    ax.sensor.settle_at(ax.actual_mm);  // the starting state, not an edge
    ax.reported_level = electrical_level(i);
    own_[i].sensor_level = ax.reported_level;
    own_[i].absolute_valid = true;
    own_[i].absolute_position_mm = encoder_reading(i);
    own_[i].drive_fault = c.fault == Fault::drive_fault;
    own_[i].stall = c.fault == Fault::stall_stuck;
    own_[i].drive_done = ax.drive.done(c);
    ax.pin_in = config_.indexer[i];
    own_[i].indexer_unlocked = false;
    set_limit_levels(i);
  }
  route_sensors(Outputs{});
}

void Simulator::reseed() {
  for (std::size_t i = 0; i < kAxisCount; ++i) {
    axes_[i].encoder_reads = 0;
    axes_[i].sensor.reseed(config_.seed, i);
    axes_[i].bounce.reseed(config_.seed, i);
  }
}

void Simulator::set_seed(std::uint64_t seed) {
  config_.seed = seed;
  reseed();
  // Fresh thresholds too, so what follows depends on the new seed alone.
  for (std::size_t i = 0; i < kAxisCount; ++i) axes_[i].sensor.configure(config_.axes[i]);
}

void Simulator::set_axis_config(std::size_t axis, const AxisConfig& config) {
  AxisConfig& c = config_.axes[axis];
  const bool sensor_changed = config.sensor_min_mm != c.sensor_min_mm ||
                              config.sensor_max_mm != c.sensor_max_mm ||
                              config.hysteresis_mm != c.hysteresis_mm ||
                              config.noise_mm != c.noise_mm;
  c = config;
  Axis& ax = axes_[axis];
  // Moving a stop onto the carriage pushes it along.
  c.actual_position_mm = ax.actual_mm = clamp_to_stops(ax.actual_mm, c);
  // Only a changed cam gets fresh thresholds: a fault or wiring write must not
  // move the edges. The state is corrected at the start of the next period.
  if (sensor_changed) ax.sensor.configure(c);
}

bool Simulator::place(std::size_t axis, double actual_mm) {
  if (axes_[axis].moving) return false;
  AxisConfig& c = config_.axes[axis];
  c.actual_position_mm = axes_[axis].actual_mm = clamp_to_stops(actual_mm, c);
  return true;
}

void Simulator::lose_steps(std::size_t axis, double mm) {
  AxisConfig& c = config_.axes[axis];
  c.actual_position_mm = axes_[axis].actual_mm = clamp_to_stops(axes_[axis].actual_mm + mm, c);
}

void Simulator::set_commutator_slave(std::size_t master, int slave) {
  config_.commutator_slave[master] = slave;
}

void Simulator::set_indexer(std::size_t axis, bool fitted) {
  if (config_.indexer[axis] == fitted) return;
  config_.indexer[axis] = fitted;
  axes_[axis].pin_in = fitted;
  axes_[axis].pin_timer_s = 0;
  own_[axis].indexer_unlocked = false;
  inputs_.axes[axis].indexer_unlocked = false;
}

void Simulator::set_estop(bool pressed) { inputs_.estop = pressed; }
void Simulator::set_start_button(bool pressed) { inputs_.start_button = pressed; }
void Simulator::set_homing_permit(bool on) { inputs_.homing_permit = on; }

bool Simulator::at_hard_stop(std::size_t axis) const {
  const AxisConfig& c = config_.axes[axis];
  const double x = axes_[axis].actual_mm;
  return std::abs(x - c.hard_stop_min_mm) <= kTouch_mm || std::abs(x - c.hard_stop_max_mm) <= kTouch_mm;
}

bool Simulator::electrical_level(std::size_t axis) const {
  const Axis& ax = axes_[axis];
  const AxisConfig& c = config_.axes[axis];
  bool contact = ax.sensor.active() != ax.bounce_odd;
  switch (c.fault) {
    case Fault::sensor_stuck_active: contact = true; break;
    case Fault::sensor_stuck_inactive: contact = false; break;
    case Fault::wire_break: return false;  // NO then reads inactive, NC reads active
    case Fault::none:
    case Fault::drive_fault:
    case Fault::stall_dead:
    case Fault::stall_stuck:
    case Fault::drive_never_answers:
    case Fault::drive_answers_at_once:
    case Fault::drive_done_lost: break;
    case Fault::indexer_stuck_locked:
    case Fault::indexer_never_locks:
    case Fault::limits_dead:
    case Fault::limits_stuck:
    case Fault::encoder_reversed: break;
  }
  return c.sensor_nc ? !contact : contact;
}

// A sensor fault forces the level: the switch's own edges no longer show.
// Any other fault (drive, indexer) leaves the switch alone.
bool Simulator::reports_edges(std::size_t axis) const {
  switch (config_.axes[axis].fault) {
    case Fault::sensor_stuck_active:
    case Fault::sensor_stuck_inactive:
    case Fault::wire_break: return false;
    case Fault::none:
    case Fault::drive_fault:
    case Fault::stall_dead:
    case Fault::stall_stuck:
    case Fault::drive_never_answers:
    case Fault::drive_answers_at_once:
    case Fault::drive_done_lost:
    case Fault::indexer_stuck_locked:
    case Fault::indexer_never_locks:
    case Fault::limits_dead:
    case Fault::limits_stuck:
    case Fault::encoder_reversed: break;
  }
  return true;
}

void Simulator::advance(const Outputs& outputs, double dt_s) {
  dt_s = std::max(dt_s, 0.0);
  for (std::size_t i = 0; i < kAxisCount; ++i) {
    const std::size_t o = driving_output(i);
    advance_axis(i, o, outputs.axes[o], connected(i, o, outputs), dt_s);
    advance_indexer(i, outputs.axes[i].indexer_unlock, dt_s);
  }
  route_sensors(outputs);
  time_s_ += dt_s;
}

std::size_t Simulator::driving_output(std::size_t axis) const {
  for (std::size_t m = 0; m < kAxisCount; ++m)
    if (m != axis && config_.commutator_slave[m] == static_cast<int>(axis)) return m;
  return axis;
}

int Simulator::wired_slave(std::size_t master) const {
  const int s = config_.commutator_slave[master];
  if (s < 0 || s >= static_cast<int>(kAxisCount) || static_cast<std::size_t>(s) == master) return -1;
  return driving_output(static_cast<std::size_t>(s)) == master ? s : -1;  // the first master claiming it
}

bool Simulator::connected(std::size_t axis, std::size_t output, const Outputs& outputs) const {
  if (output != axis) return true;  // a commutator slave: the master's output always reaches it
  // A master's own carriage, unless its commutator routes the output to the slave.
  return !(wired_slave(axis) >= 0 && outputs.axes[axis].commutator_output);
}

bool Simulator::in_motion(std::size_t axis, const Outputs& next) const {
  if (axes_[axis].moving) return true;
  const std::size_t o = driving_output(axis);
  const AxisOutputs& drive = next.axes[o];
  return connected(axis, o, next) &&
         (drive.motor.velocity_mm_per_s != 0 || drive.motion.target_velocity_mm_per_s != 0);
}

double Simulator::quiet_for_s(const Outputs& outputs) const {
  double quiet_s = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < kAxisCount; ++i) {
    const Axis& ax = axes_[i];
    const AxisConfig& c = config_.axes[i];
    const std::size_t o = driving_output(i);
    if (in_motion(i, outputs) || !ax.drive.at_rest(out_request(i, o, outputs.axes[o])) || ax.held_since_s >= 0)
      return 0;
    if (ax.bounce.pending() > 0) quiet_s = std::min(quiet_s, ax.bounce.next_s() - time_s_);
    // The pin moves once the unlock output has wanted it to for its delay (advance_indexer).
    const bool wants_in = !outputs.axes[i].indexer_unlock;
    if (config_.indexer[i] && c.fault != Fault::indexer_stuck_locked && wants_in != ax.pin_in &&
        !(wants_in && c.fault == Fault::indexer_never_locks)) {
      const double delay_s = (wants_in ? c.lock_delay_ms : c.unlock_delay_ms) / 1000.0;
      quiet_s = std::min(quiet_s, delay_s - ax.pin_timer_s);
    }
  }
  return std::max(quiet_s, 0.0);
}

void Simulator::advance_axis(std::size_t i, std::size_t output, const AxisOutputs& out, bool linked,
                             double dt_s) {
  Axis& ax = axes_[i];
  AxisConfig& c = config_.axes[i];
  AxisInputs& in = own_[i];
  in.sensor_edges = InputEdges{};
  in.index_edges = InputEdges{};
  in.index_level = false;  // pulses are far shorter than a period

  // A fault or wiring change since the last period: the level steps at its start.
  if (electrical_level(i) != ax.reported_level) in.sensor_edges.add(0.0);

  // Slip: this carriage minus the position of the output that drives it.
  SensorEvents events;
  const double slip_start_mm = ax.actual_mm - out.motor.position_mm;
  // The carriage jumped (place, lose_steps) or the cam moved while it stood still.
  if (ax.sensor.settle_at(ax.actual_mm)) {
    events.add(SensorEvent{0.0, ax.sensor.active(), ax.actual_mm, slip_start_mm});
  }

  const MotionPath motor = plan_path(out.motor, out.motion, dt_s);
  // A faulted drive, or a master carriage while the commutator feeds its slave,
  // stands still: the output's steps do not reach it. An indexer's pin holds
  // the carriage for the whole period it is in at the start of (the steps
  // are lost, as against a stop).
  const bool motor_runs = motor.end.position_mm != out.motor.position_mm || out.motor.velocity_mm_per_s != 0 ||
                          motor.end.velocity_mm_per_s != 0;
  ax.moved_while_locked = linked && ax.pin_in && motor_runs;
  const bool follows = linked && c.fault != Fault::drive_fault && !ax.pin_in;
  const CarriagePath carriage = carriage_path(out.motor, motor, ax.actual_mm, stops_of(c), follows);
  for (std::size_t p = 0; p < carriage.count; ++p) {
    const CarriagePiece& piece = carriage.pieces[p];
    ax.sensor.sweep(piece.motion, piece.slip_mm, events);
    add_index_crossings(piece.motion, c.index_pitch_mm, c.index_offset_mm, in.index_edges);
  }
  ax.moving = linked && motor.end.velocity_mm_per_s != 0;
  ax.actual_mm = carriage.count ? carriage.end_mm : ax.actual_mm;
  // A drive homing itself moves the carriage without steps (the slip
  // changes); the sensor takes the new place at the next period's start.
  const Stops stops = stops_of(c);
  if (ax.drive.advance(out_request(i, output, out), c, stops.min_mm, stops.max_mm, ax.actual_mm, dt_s))
    ax.moving = true;
  c.actual_position_mm = ax.actual_mm;

  // True edges and bounce toggles in time order; each one flips the contact.
  const bool report = reports_edges(i);
  const double bounce_s = c.bounce_ms / 1000.0;
  double toggle_s = 0;
  auto flush_bounce = [&](double until_s) {
    while (ax.bounce.pop_due(until_s, toggle_s)) {
      ax.bounce_odd = !ax.bounce_odd;
      if (report) in.sensor_edges.add(toggle_s - time_s_);
    }
  };
  for (std::size_t e = 0; e < events.count; ++e) {
    const SensorEvent& ev = events.items[e];
    const double t_s = time_s_ + ev.time_s;
    flush_bounce(t_s);
    ax.ring.push(EdgeRecord{i, t_s, ev.to_active, ev.actual_mm, ev.actual_mm - ev.slip_mm, output});
    if (report) in.sensor_edges.add(ev.time_s);
    ax.bounce.schedule(t_s, bounce_s);
  }
  flush_bounce(time_s_ + dt_s);

  ax.reported_level = electrical_level(i);
  in.sensor_level = ax.reported_level;
  in.absolute_valid = true;
  in.absolute_position_mm = encoder_reading(i);
  in.drive_fault = c.fault == Fault::drive_fault;
  in.stall = stall_output(i, carriage, out.motor.position_mm, motor.end.position_mm);
  in.drive_done = ax.drive.done(c);
  set_limit_levels(i);
}

// Its own draws (stream 1000 + axis, apart from the stall's), and only with
// noise: an exact encoder leaves every other draw as it was.
double Simulator::encoder_reading(std::size_t i) {
  Axis& ax = axes_[i];
  const AxisConfig& c = config_.axes[i];
  const double carriage = c.fault == Fault::encoder_reversed ? -ax.actual_mm : ax.actual_mm;
  double reading = carriage + c.absolute_offset_mm;
  if (c.encoder_noise_mm > 0) {
    // Box-Muller from two draws of this reading.
    const double u1 = 1.0 - fraction(config_.seed, 1000 + i, 2 * ax.encoder_reads);
    const double u2 = fraction(config_.seed, 1000 + i, 2 * ax.encoder_reads + 1);
    ++ax.encoder_reads;
    reading += c.encoder_noise_mm * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }
  if (c.encoder_resolution_mm > 0) reading = std::round(reading / c.encoder_resolution_mm) * c.encoder_resolution_mm;
  return reading;
}

bool Simulator::limit_active(std::size_t axis, bool max_end) const {
  const AxisConfig& c = config_.axes[axis];
  if (c.fault == Fault::limits_stuck) return true;
  if (c.fault == Fault::limits_dead) return false;
  const double x = axes_[axis].actual_mm;
  return max_end ? x >= c.limit_max_mm : x <= c.limit_min_mm;
}

// Levels at the end of the period (the engine reads limit switches by level).
void Simulator::set_limit_levels(std::size_t axis) {
  const bool nc = config_.axes[axis].limits_nc;
  own_[axis].limit_min_level = limit_active(axis, false) != nc;
  own_[axis].limit_max_level = limit_active(axis, true) != nc;
}


bool Simulator::stall_output(std::size_t i, const CarriagePath& path, double motor_start_mm, double motor_end_mm) {
  Axis& ax = axes_[i];
  const AxisConfig& c = config_.axes[i];
  if (c.fault == Fault::stall_stuck) return true;
  // Driving into a stop: the carriage ends the period on it and the motor
  // moved further toward it.
  const Stops stops = stops_of(c);
  const bool on_min = std::abs(ax.actual_mm - stops.min_mm) <= kTouch_mm && motor_end_mm < motor_start_mm;
  const bool on_max = std::abs(ax.actual_mm - stops.max_mm) <= kTouch_mm && motor_end_mm > motor_start_mm;
  if (!on_min && !on_max) {
    ax.held_since_s = -1;
    return false;
  }
  if (ax.held_since_s < 0) {
    // Held since the start of the last piece of the period: the carriage at rest on the stop.
    double since = time_s_;
    if (path.count > 0) since += path.pieces[path.count - 1].motion.start_s;
    ax.held_since_s = since;
    ax.stall_after_s = (c.stall_detect_ms + c.stall_spread_ms * fraction(config_.seed, i, ax.contacts++)) / 1000.0;
  }
  if (c.fault == Fault::stall_dead) return false;
  const double now = time_s_ + (path.count > 0 ? path.pieces[path.count - 1].motion.start_s +
                                                     path.pieces[path.count - 1].motion.duration_s
                                               : 0.0);
  return now - ax.held_since_s >= ax.stall_after_s;
}

// The home request reaches the carriage's own drive only (a commutator slave
// has none of its own on the master's output).
bool Simulator::out_request(std::size_t axis, std::size_t output, const AxisOutputs& out) const {
  return output == axis && out.drive_request;
}

// The pin moves lock_delay / unlock_delay after the unlock output asks it to;
// the unlocked input reports it out. Faults: stuck locked puts it in at once
// and keeps it there; never locks keeps it out once out.
void Simulator::advance_indexer(std::size_t i, bool unlock_output, double dt_s) {
  Axis& ax = axes_[i];
  const AxisConfig& c = config_.axes[i];
  if (!config_.indexer[i]) {
    ax.pin_in = false;
    own_[i].indexer_unlocked = false;  // nothing wired
    return;
  }
  const bool wants_in = !unlock_output;
  if (c.fault == Fault::indexer_stuck_locked) {
    ax.pin_in = true;
    ax.pin_timer_s = 0;
  } else if (wants_in != ax.pin_in && !(wants_in && c.fault == Fault::indexer_never_locks)) {
    ax.pin_timer_s += dt_s;
    const double delay_s = (wants_in ? c.lock_delay_ms : c.unlock_delay_ms) / 1000.0;
    if (ax.pin_timer_s >= delay_s) {
      ax.pin_in = wants_in;
      ax.pin_timer_s = 0;
    }
  } else {
    ax.pin_timer_s = 0;
  }
  own_[i].indexer_unlocked = !ax.pin_in;
}

void Simulator::route_sensors(const Outputs& outputs) {
  for (std::size_t m = 0; m < kAxisCount; ++m) {
    inputs_.axes[m] = own_[m];
    const int s = wired_slave(m);
    // The diverter puts the slave's switch on the master's input; switching it
    // is a plain level change, with no edge time.
    if (outputs.axes[m].commutator_output && s >= 0) {
      inputs_.axes[m].sensor_level = own_[s].sensor_level;
      inputs_.axes[m].sensor_edges = own_[s].sensor_edges;
    }
  }
}

std::size_t Simulator::edges(std::size_t axis, std::span<EdgeRecord> out) const {
  return axes_[axis].ring.copy(out);
}

std::vector<EdgeRecord> Simulator::edges(std::size_t axis) const {
  std::vector<EdgeRecord> out(axes_[axis].ring.size());
  axes_[axis].ring.copy(out);
  return out;
}

std::optional<EdgeRecord> Simulator::last_edge(std::size_t axis) const {
  return axes_[axis].ring.last();
}

std::optional<EdgeRecord> Simulator::last_edge(std::size_t axis, bool to_active) const {
  return axes_[axis].ring.last(to_active);
}

}  // namespace homing::sim
