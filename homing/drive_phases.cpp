// Drive-performed homing: the drive homes itself on its own sensor at its own
// speeds while the home request is on; the module sends no steps, so the
// motor position it counts stays put while the carriage moves, and the home
// position is assigned where the drive reports done.
#include "phase_runner.hpp"

namespace homing {

// The request is on while this phase runs (output_routing.cpp). A done that
// was on before the request counts only after it went off: a drive drops its
// home done when it begins homing, so a stale done is no answer. A done
// sooner than kDriveMinHomingTime_s (or one never dropped by then) follows
// no homing.
void PhaseRunner::drive_homing() {
  auto& d = run.phase_data<phase_data::DriveHoming>();
  const bool done = run.readings.drive_done;
  // A locking indexer still unlocking holds the request back (the drive
  // would drive against the pin): its clock starts once the axis may move.
  if (entry() || !run.indexer.lets_move()) {
    d.request_s = ctx.time_s;
    d.done_seen_off = !done;
    run.command = stop_command(accel);  // the drive moves the carriage; the motor output stays at rest
    return;
  }
  const double waited_s = ctx.time_s - d.request_s;
  if (!done) {
    d.done_seen_off = true;
  } else if (d.done_seen_off && waited_s < kDriveMinHomingTime_s) {
    return fail(AlarmCode::drive_answered_at_once, waited_s);
  } else if (d.done_seen_off && at_rest()) {
    run.drive_referenced = true;
    return enter(row().after(Phase::drive_homing));
  }
  if (!d.done_seen_off && waited_s >= kDriveMinHomingTime_s)
    return fail(AlarmCode::drive_answered_at_once, waited_s);
  if (waited_s >= s.drive_home_timeout_s) return fail(AlarmCode::drive_no_answer, waited_s);
}

}  // namespace homing
