// The commissioning measurement's phase (measure.hpp): the axis is homed;
// it travels at latch feedrate away from home until the opposite end is
// told, bounded by max_seek_travel from where the phase began. A limit
// switch there is the end it looks for, not a hard limit: the axis brakes,
// leaves the switch again at latch feedrate (within max_backoff) and stops
// just off it, still homed. A hard stop is pushed into at reduced current,
// as hard-stop homing pushes, until the stall input comes; the motor may
// lose steps against the stop, so the axis is no longer homed from the
// start of that push, and it ends pull_off away from the stop (and the
// pre-move's distance, when a pre-move always runs, so that the home cycle
// that must follow does not pre-move into the stop).
#include "phase_runner.hpp"

namespace homing {

using MeasureStep = phase_data::Measure::Step;

void PhaseRunner::measure_travel() {
  auto& m = run.phase_data<phase_data::Measure>();
  if (entry()) {
    measure_begin(m);
    if (!run.in_cycle || run.alarm) return;  // stall_at_start
  }
  switch (m.step) {
    case MeasureStep::travel: return measure_travel_on(m);
    case MeasureStep::brake: return measure_brake(m);
    case MeasureStep::leave: return measure_leave(m);
    case MeasureStep::settle: return measure_settle(m);
  }
}

// Away from home: opposite to the seek (the sensor or the stop lies toward dir).
void PhaseRunner::measure_begin(phase_data::Measure& m) {
  m.step = MeasureStep::travel;
  m.toward = -dir;
  m.start_mm = run.motor.position_mm;
  run.target_mm = m.start_mm + m.toward * s.max_seek_travel_mm;
  if (travel_end(s) != TravelEnd::hard_stop) return;
  // What tells the stop must not tell it before the push.
  if (run.readings.stall) return fail(AlarmCode::stall_at_start);
  run.lose_reference();
  run.push_output = true;
}

bool PhaseRunner::measure_end_told(const phase_data::Measure& m) const {
  if (travel_end(s) == TravelEnd::hard_stop) return run.readings.stall;
  return run.readings.limit_toward(m.toward);
}

void PhaseRunner::measure_travel_on(phase_data::Measure& m) {
  if (measure_end_told(m)) {
    m.end_mm = run.motor.position_mm;
    m.step = MeasureStep::brake;
    run.command = stop_command(accel);
    return;
  }
  move_to(run.target_mm, latch_v);
  if (arrived()) fail(AlarmCode::travel_end_not_found, std::abs(run.motor.position_mm - m.start_mm));
}

// At rest after the end: the figures are taken, then off the end again.
void PhaseRunner::measure_brake(phase_data::Measure& m) {
  run.command = stop_command(accel);
  if (!at_rest()) return;
  if (travel_end(s) == TravelEnd::hard_stop) {
    // Against the stop the motor rests where the carriage does: its rest
    // is the end, as hard-stop homing takes its reference.
    m.end_mm = run.motor.position_mm;
    run.push_output = false;
  }
  measure_record(m);
  if (travel_end(s) == TravelEnd::hard_stop) {
    // Unhomed there, it is homed again next: a pre-move that always runs
    // goes away from home first, toward this stop, at seek feedrate and full
    // current. It ends far enough off for that (campaign seed 187000060).
    const double pre_move = s.pre_move_mode == PreMove::always ? s.pre_move_distance_mm : 0.0;
    m.step = MeasureStep::settle;
    run.target_mm = run.motor.position_mm - m.toward * (s.pull_off_mm + pre_move);
    return;
  }
  m.step = MeasureStep::leave;
  run.target_mm = run.motor.position_mm - m.toward * s.max_backoff_mm;
}

// The longest seek a cycle may need starts at the far end and runs to
// where the sensor (or stop) is told: the reference, plus the stop
// distance a seek may take past its trigger.
void PhaseRunner::measure_record(const phase_data::Measure& m) {
  const double longest_seek_mm = std::abs(m.end_mm - run.reference_mm) + s.max_stop_distance_mm;
  run.measurement = measurement_from(s, m.end_mm + run.offset_mm, m.toward, longest_seek_mm);
}

void PhaseRunner::measure_leave(phase_data::Measure& m) {
  if (!run.readings.limit_toward(m.toward)) {
    m.step = MeasureStep::settle;
    run.command = stop_command(accel);
    run.target_mm = run.motor.position_mm;
    return;
  }
  move_to(run.target_mm, latch_v);
  if (arrived()) fail(AlarmCode::not_released, std::abs(run.motor.position_mm - m.end_mm));
}

void PhaseRunner::measure_settle(phase_data::Measure&) {
  if (travel_end(s) == TravelEnd::hard_stop) {
    move_to(run.target_mm, seek_v);
    if (arrived()) enter(Phase::done);
    return;
  }
  run.command = stop_command(accel);
  if (at_rest()) enter(Phase::done);
}

}  // namespace homing
