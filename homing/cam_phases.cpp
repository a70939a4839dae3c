// Home cam in mid-travel between two limit switches (CiA 402 homing methods
// 7-14 and 23-30, Beckhoff MC_StepLimitSwitch). The axis seeks the cam in
// its direction; meeting the limit switch ahead first, it brakes there and
// searches the other way. On the cam it brakes, then leaves the cam at latch
// feedrate across the configured edge (cam_edge): that release is the
// reference, crossed the same way whichever side the cam was found from.
#include <cmath>

#include "mutation.hpp"
#include "phase_runner.hpp"

namespace homing {

void PhaseRunner::fail_limit(AlarmCode code, double toward) {
  ctx.alarms.raise(axis_bit(axis), Alarm{code, run.phase, AxisField::none, run.machine_position_mm(),
                                         static_cast<std::uint8_t>(toward < 0 ? 1 : 2)});
}

// A homing motion never starts toward an active limit switch, as a jog or a
// move toward one is refused: the alarm comes before a period of motion
// (else each cycle started on a tripped switch would creep deeper past it).
// Only the search that reverses at the switches may head for one.
bool PhaseRunner::starts_into_limit(double target_mm) {
  const AxisReadings& in = run.readings;
  const double toward = target_mm - run.motor.position_mm;
  if (!settings.axes[axis].limits_fitted || !at_rest() || toward == 0 || reverses_at_limits(run.phase) ||
      !in.limit_toward(toward))
    return false;
  run.command = stop_command(accel);
  if (in.limit_min && in.limit_max) {
    fail_limit(AlarmCode::both_limits_active, toward);
    return true;
  }
  fail_limit(AlarmCode::limit_in_homing, toward);
  run.limit_tripped = true;
  run.limit_side = toward < 0 ? -1 : 1;
  return true;
}

void PhaseRunner::cam_triggered() {
  const phase_data::Stop trigger{edge_mm(), dt()};
  enter(Phase::cam_stop);
  run.phase_data<phase_data::Stop>() = trigger;
}

void PhaseRunner::cam_seek() {
  const AxisReadings& in = run.readings;
  if (in.limit_min && in.limit_max) return fail_limit(AlarmCode::both_limits_active, dir);
  if (entry()) {
    if (active()) {
      // Already on the cam: no seek, no stop; leave it across its reference edge.
      run.reach(Reached::stopped_on_sensor);
      return enter(Phase::cam_latch);
    }
    if (in.limit_toward(dir) && !planted(Mutant::home_cam_search_ignores_limit_switch))
      return enter(Phase::limit_reversal);
    run.target_mm = run.phase_start_mm + dir * s.max_seek_travel_mm;
  }
  if (edge_to(true)) return cam_triggered();
  if (in.limit_toward(dir) && !planted(Mutant::home_cam_search_ignores_limit_switch))
    return enter(Phase::limit_reversal);
  move_to(run.target_mm, seek_v);
  if (arrived()) fail(AlarmCode::sensor_not_found, travelled());
}

// Met the limit switch ahead before the cam: brake within the acceleration
// (the switch has limit_overtravel before the stop), then search back the
// whole travel for the cam. Meeting the other limit switch means there is
// no cam between them.
void PhaseRunner::limit_reversal() {
  const AxisReadings& in = run.readings;
  if (in.limit_min && in.limit_max) return fail_limit(AlarmCode::both_limits_active, dir);
  entry();  // no entry action: the braking starts at once
  phase_data::LimitReversal& rev = run.phase_data<phase_data::LimitReversal>();
  if (!rev.braked) {
    run.command = stop_command(accel);
    if (!at_rest()) return;
    rev.braked = true;
    // A cam right at the limit may hold the carriage now: it is on the cam.
    if (active()) {
      run.reach(Reached::stopped_on_sensor);
      return enter(Phase::cam_latch);
    }
    run.phase_start_mm = run.motor.position_mm;
    run.target_mm = run.phase_start_mm - dir * s.max_seek_travel_mm;
  }
  if (edge_to(true)) return cam_triggered();
  if (in.limit_toward(-dir)) return fail_limit(AlarmCode::cam_not_found, -dir);
  move_to(run.target_mm, seek_v);
  if (arrived()) fail(AlarmCode::sensor_not_found, travelled());
}

// The stop after a seek's trigger (search_phases.cpp), in whichever
// direction the search ran: the cam must hold the sensor through the stop.
void PhaseRunner::cam_stop() {
  if (stopped_on_sensor()) enter(Phase::cam_latch);
}

// Off the cam at latch feedrate toward its reference side, bounded by
// max_backoff (which must cover the cam's length: the far edge may be the
// reference).
void PhaseRunner::cam_latch() {
  if (entry()) run.target_mm = run.phase_start_mm + cam_side() * s.max_backoff_mm;
  if (edge_to(false)) {
    run.reach(Reached::released);
    return reference_found(edge_mm());
  }
  move_to(run.target_mm, latch_v);
  if (arrived()) fail(AlarmCode::not_released, travelled());
}

}  // namespace homing
