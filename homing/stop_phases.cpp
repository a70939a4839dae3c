// Hard-stop homing: no switch. The axis moves into its mechanical stop at
// latch feedrate with the push output on (reduced current) until the stop is
// told: by the drive's stall input, or (stall_detect following_error) by the
// encoder, once the carriage has fallen behind its steps by more than
// max_following_error. The carriage then rests against the stop, whatever
// steps the motor lost meanwhile, so the motor position at rest is the
// reference. Bounded by max_seek_travel and by stall_timeout_ms.
#include "mutation.hpp"
#include "phase_runner.hpp"

namespace homing {

namespace {
// The carriage only ever follows the push toward the stop, or stops: an
// encoder that counts away from it by this share of max_following_error
// counts against the steps (reversed, or another axis's encoder). Well
// above what its noise can do (the rule following_error_in_noise), well
// below the half of the limit a reversed encoder shows when the following
// error (twice its travel) reaches the limit.
constexpr double kReversedShare = 0.25;
}  // namespace

// What tells the stop must not tell it before the push: nothing could be
// learnt from it. The encoder must give a position to follow the steps by.
std::optional<AlarmCode> PhaseRunner::push_cannot_start() const {
  if (detects_stop_by_following_error(s)) {
    if (!run.readings.absolute_valid) return AlarmCode::encoder_fault;
    return std::nullopt;
  }
  if (run.readings.stall) return AlarmCode::stall_at_start;
  return std::nullopt;
}

// How far the carriage has fallen behind its steps since the push began,
// and how far it followed them (both toward the stop).
PhaseRunner::Following PhaseRunner::following(const phase_data::PushToStop& push) const {
  const double followed = dir * (run.readings.absolute_mm - push.encoder_start_mm);
  const double commanded = dir * (run.motor.position_mm - push.motor_start_mm);
  return {commanded - followed, followed};
}

void PhaseRunner::push_to_stop() {
  phase_data::PushToStop& push = run.phase_data<phase_data::PushToStop>();
  const bool by_encoder = detects_stop_by_following_error(s);
  if (entry()) {
    if (const auto cannot = push_cannot_start()) return fail(*cannot);
    run.push_output = true;
    push.start_s = ctx.time_s;
    push.motor_start_mm = run.motor.position_mm;
    push.encoder_start_mm = run.readings.absolute_mm;
    run.target_mm = run.phase_start_mm + dir * s.max_seek_travel_mm;
  }
  if (!push.stalled && by_encoder) {
    // An encoder lost or counting the wrong way tells nothing of the stop.
    if (!run.readings.absolute_valid) return fail(AlarmCode::encoder_fault);
    const Following f = following(push);
    if (f.followed_mm < -kReversedShare * s.max_following_error_mm && !planted(Mutant::reversed_encoder_unchecked))
      return fail(AlarmCode::encoder_reversed, -f.followed_mm);
  }
  const bool told = by_encoder ? following(push).error_mm > s.max_following_error_mm : run.readings.stall;
  if (!push.stalled && told) {
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
