// End-of-travel limit switches as hard limits (docs/limit-switches.md): an
// axis with limits_fitted that moves toward an active limit switch stops
// with an alarm at its acceleration, in every phase except the home cam's
// search, which reverses there itself (cam_phases.cpp). The trip is
// recovered as a shared limit's is: the reset is taken while the axis still
// stands on the switch, and a jog away from it (only away) is allowed until
// it releases (limit_tripped, limit_side; jog_move.cpp).
#include "engine.hpp"
#include "mutation.hpp"

namespace homing {

void Engine::check_limit_switches(const Settings& settings) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    const AxisSettings& s = settings.axes[a];
    const AxisReadings& in = run.readings;
    if (run.limit_tripped && run.limit_side != 0 && !in.limit_toward(run.limit_side)) {
      run.limit_tripped = false;
      run.limit_side = 0;
    }
    // An axis with its alarm only brakes, unless a failure policy sends it back (failure_policy.cpp).
    if (!s.limits_fitted || (run.alarm && run.phase != Phase::return_to_start)) continue;
    const double pos = run.machine_position_mm();
    // Both ends at once cannot be: a broken wire (NC) or a wrong limits_nc.
    // Only judged while the axis would move, so a module wired wrongly can
    // still be set right at rest.
    if (in.limit_min && in.limit_max) {
      if (run.busy())
        raise(settings, axis_bit(a), Alarm{AlarmCode::both_limits_active, Phase::idle, AxisField::none, pos, 0});
      continue;
    }
    if (run.in_cycle && reverses_at_limits(run.phase)) continue;
    if (!run.in_cycle && planted(Mutant::limit_switch_ignored_outside_homing)) continue;
    // Moving toward it, or come to rest on it within the period that just
    // ended (a target a hair past the switch, a late period): a trip all the same.
    const double v = run.motor.velocity_mm_per_s;
    const double heading = v != 0 ? v : run.motor.position_mm - run.period_start.position_mm;
    if (heading == 0) continue;
    const std::int8_t toward = heading < 0 ? -1 : 1;
    if (!in.limit_toward(toward)) continue;
    // A measurement looks for the limit switch it travels toward: its end, not a hard limit.
    if (const auto* m = run.phase_data_if<phase_data::Measure>();
        run.in_cycle && run.phase == Phase::measure_travel && m && m->toward == toward)
      continue;
    // A hard-stop home pushes into the stop its limit switch stands before:
    // that switch is on the way to the reference, not a hard limit (the push
    // is bounded by max_seek_travel and stall_timeout, as without limits).
    if (run.in_cycle && run.phase == Phase::push_to_stop && toward == (s.direction == Direction::positive ? 1 : -1)) continue;
    // Reset while still braking onto it: the trip is known, no second alarm.
    // Only that braking: a motion started since (a homing phase; jogs and
    // moves toward it are refused) trips the switch again at once.
    const bool braking = !run.in_cycle && (run.phase == Phase::stopping || run.phase == Phase::idle);
    if (run.limit_tripped && run.limit_side == toward && braking) continue;
    const AlarmCode code = run.in_cycle ? AlarmCode::limit_in_homing : AlarmCode::limit_switch;
    raise(settings, axis_bit(a),
          Alarm{code, Phase::idle, AxisField::none, pos, static_cast<std::uint8_t>(toward < 0 ? 1 : 2)});
    run.limit_tripped = true;
    run.limit_side = toward;
  }
}

}  // namespace homing
