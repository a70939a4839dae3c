// Finding the sensor: the pre-move, a gantry's clearing of its sensors, the seek, the stop after the trigger and the push
// into the mechanical stop.
#include <cmath>

#include "phase_runner.hpp"

namespace homing {

void PhaseRunner::pre_move() {
  if (entry()) {
    // A gantry decides for the pair: either side on its sensor counts.
    const bool needed = s.pre_move_mode == PreMove::always ||
                        (s.pre_move_mode == PreMove::if_sensor_active && (active() || partner_active()));
    if (!needed) return enter(row().after(Phase::pre_move));
    run.target_mm = run.motor.position_mm - dir * s.pre_move_distance_mm;
  }
  move_to(run.target_mm, seek_v);
  if (arrived()) enter(row().after(Phase::pre_move));
}

// A gantry with either side on its sensor at the start of the seek first
// moves off both sensors together (latch feedrate, bounded by max_backoff),
// then seeks: both sides meet their sensors within their skew, so the pair
// cannot rack while one side seeks alone.
void PhaseRunner::clear_sensors() {
  if (entry()) run.target_mm = run.motor.position_mm - dir * s.max_backoff_mm;
  if (!active() && !partner_active()) {
    enter(Phase::seek);
    run.phase_data<phase_data::Seek>().at_latch = true;
    return;
  }
  move_to(run.target_mm, latch_v);
  if (!arrived()) return;
  // The alarm goes to the side whose sensor still holds: that is the sensor to check.
  AxisMask holding = 0;
  if (active()) holding |= axis_bit(axis);
  if (partner_active()) holding |= axis_bit(static_cast<std::size_t>(partner));
  ctx.alarms.raise(holding, Alarm{AlarmCode::not_released, run.phase, AxisField::none, travelled(), 0});
}

void PhaseRunner::seek() {
  if (entry()) {
    if (software_pair() && (active() || partner_active())) return enter(Phase::clear_sensors);
    if (active()) {
      // Already on the sensor (MASSO): no seek, no stop; find the edge.
      run.reach(Reached::stopped_on_sensor);
      return after_stop();
    }
    // Bounded by max_seek_travel, braking in time to rest at its end; a
    // commutator slave alone by how far it may rack the pair.
    run.target_mm = run.phase_start_mm + dir * (commutator_slave() ? travel_within_square() : s.max_seek_travel_mm);
  }
  if (edge_to(true)) {
    const phase_data::Stop trigger{edge_mm(), dt()};
    run.edges.seek_seen = true;
    run.edges.seek_mm = edge_mm();
    enter(Phase::stop);
    run.phase_data<phase_data::Stop>() = trigger;
    return;
  }
  // Just off both sensors, the pair meets them again within the clearing
  // distance: at latch feedrate, so the side that meets its sensor first
  // does not stop much shorter than the other and rack the pair.
  const auto* seek = run.phase_data_if<phase_data::Seek>();
  move_to(run.target_mm, seek && seek->at_latch ? latch_v : seek_v);
  if (arrived()) {
    if (commutator_slave()) return fail_off_square();
    return fail(AlarmCode::sensor_not_found, travelled());
  }
}

void PhaseRunner::stop() {
  if (stopped_on_sensor()) after_stop();
}

// The stop after a trigger, for every method that seeks a sensor: true in the
// period the axis rests on the sensor within max_stop_distance; an alarm when
// the sensor released during the stop or the stop ran too far.
bool PhaseRunner::stopped_on_sensor() {
  if (entry()) run.command = stop_command(accel);
  if (edge_to(false)) {
    // The figure: how far past the trigger the sensor was seen released,
    // to hold against the stop distance the text names.
    fail(AlarmCode::overrun_during_stop,
         std::abs(run.motor.position_mm - run.phase_data<phase_data::Stop>().trigger_mm));
    return false;
  }
  if (!at_rest()) return false;
  // A release during the stop may still be in its debounce time when the
  // axis comes to rest: wait for the verdict, or back-off would take that
  // release (inside the stop) for its reference edge.
  const Debouncer& filter = ctx.input.filter;
  if (filter.raw() != filter.stable()) return false;
  // One control period of travel is allowed on top: the trigger cannot be
  // seen before the period in which it happened has ended. That is the
  // period the trigger was seen in (possibly a late one), not the current.
  const phase_data::Stop& trigger = run.phase_data<phase_data::Stop>();
  const double past = std::abs(run.motor.position_mm - trigger.trigger_mm);
  if (past > s.max_stop_distance_mm + seek_v * trigger.trigger_period_s + 1e-9) {
    fail(AlarmCode::stop_distance_exceeded, past);
    return false;
  }
  run.reach(Reached::stopped_on_sensor);
  return true;
}

void PhaseRunner::after_stop() {
  const Phase next = row().after(Phase::stop);
  // A software gantry turns back from its sensors together, both from rest
  // in one period, as at every edge after (pair_phases.cpp).
  if (partner >= 0 && software_pair()) return wait_for(Wait::partner_stopped, next);
  enter(next);
}

void PhaseRunner::push() {
  if (entry()) {
    run.push_output = true;
    run.target_mm = run.motor.position_mm + dir * s.push_distance_mm;
  }
  move_to(run.target_mm, latch_v);
  if (arrived()) {
    run.push_output = false;
    enter(row().after(Phase::push));
  }
}

// A commutator slave seeks alone while its master holds: it may bring the
// pair back to square and up to max_misalignment beyond it, or stay as far
// out on its own side as the cycle found it (gantry_guard.cpp).
double PhaseRunner::travel_within_square() const {
  const SquareBand band = square_band(run.pair_square_mm, run.pair_rel0_mm, s.max_misalignment_mm);
  const double off = band.off_square(run.motor.position_mm, partner_run().motor.position_mm);
  return std::max(0.0, ((dir > 0 ? band.high_mm : band.low_mm) - off) * dir);
}

void PhaseRunner::fail_off_square() {
  const SquareBand band = square_band(run.pair_square_mm, run.pair_rel0_mm, s.max_misalignment_mm);
  Alarm alarm{AlarmCode::misalignment, run.phase, AxisField::max_misalignment,
              std::abs(band.off_square(run.motor.position_mm, partner_run().motor.position_mm)), 0};
  alarm.side = GantrySide::slave_no_sensor;
  alarm.rack_at_start_mm = band.rack_at_start_mm;
  ctx.alarms.raise(axis_bit(axis), alarm);
}

}  // namespace homing
