// Hard-stop homing: no switch. The axis moves into its mechanical stop at
// latch feedrate with the push output on (reduced current) until the drive
// reports a stall; the carriage then rests against the stop, whatever steps
// the motor lost meanwhile, so the motor position at rest is the reference.
// Bounded by max_seek_travel and by stall_timeout_ms.
#include "phase_runner.hpp"

namespace homing {

void PhaseRunner::push_to_stop() {
  phase_data::PushToStop& push = run.phase_data<phase_data::PushToStop>();
  if (entry()) {
    // A stall already reported means nothing can be learnt from the next one.
    if (run.readings.stall) return fail(AlarmCode::stall_at_start);
    run.push_output = true;
    push.start_s = ctx.time_s;
    run.target_mm = run.phase_start_mm + dir * s.max_seek_travel_mm;
  }
  if (!push.stalled && run.readings.stall) {
    push.stalled = true;
    run.command = stop_command(accel);
  }
  if (push.stalled) {
    // The current stays reduced until the motor rests against the stop.
    if (!at_rest()) return;
    run.push_output = false;
    return reference_found(run.motor.position_mm);
  }
  const double pushing_s = ctx.time_s - push.start_s;
  // An alarm keeps the push output on while the motor brakes (alarm_path.cpp).
  if (pushing_s * 1000.0 >= s.stall_timeout_ms) return fail(AlarmCode::stall_timeout, pushing_s);
  move_to(run.target_mm, latch_v);
  if (arrived()) fail(AlarmCode::stop_not_found, travelled());
}

}  // namespace homing
