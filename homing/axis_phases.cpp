// One axis in a homing cycle: how it begins (its mode's first phase), which phase
// function runs, and the period loop that runs a new phase's entry at once.
#include "engine.hpp"
#include "phase_runner.hpp"

namespace homing {

PhaseRunner::PhaseRunner(const PhaseContext& context, const Settings& st, std::size_t a)
    : ctx(context), settings(st), axis(a), run(context.run), s(st.axes[a]) {
  is_slave = gantry_master(st, a) >= 0;
  partner = gantry_partner(st, a);
  // The slave motor alone only corrects the gantry's skew (the gantry guard
  // stops it before the pair could rack beyond max_misalignment).
  if (commutator_slave()) s = commutator_slave_homing(s);
  dir = s.direction == Direction::positive ? 1.0 : -1.0;
  seek_v = mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min);
  latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
  accel = s.acceleration_mm_per_s2;
}

void PhaseRunner::begin() {
  // A reference check measures nothing of the switch's health: the last
  // cycle's figures stay.
  if (run.checking) return enter(Phase::reference_check);
  run.latch = {};
  run.health = {};
  run.edges = {};
  run.edges.transitions_at_start = ctx.input.filter.transitions();
  run.edges.accepted_at_start = ctx.input.filter.accepted();
  run.entered = false;
  run.phase_start_mm = run.motor.position_mm;
  if (commutator_slave()) {
    run.follow_master = true;
    return wait_for(Wait::master_at_reference, Phase::align_slave);
  }
  const Phase first = row().first();
  if (first == Phase::done) {  // a method that does not home counts as homed
    run.home = home_frame(settings.axes[axis]);
    run.set_phase(Phase::done);
    return;
  }
  // A method that only assigns moves nothing: its coordinate is given at once.
  if (first == Phase::assign) return assign();
  enter(first);
}

void PhaseRunner::dispatch() {
  switch (run.phase) {
    case Phase::pre_move: return pre_move();
    case Phase::clear_sensors: return clear_sensors();
    case Phase::seek: return seek();
    case Phase::stop: return stop();
    case Phase::push: return push();
    case Phase::push_to_stop: return push_to_stop();
    case Phase::back_off: return back_off();
    case Phase::reapproach: return reapproach();
    case Phase::index: return index();
    case Phase::pull_off: return pull_off();
    case Phase::assign: return assign();
    case Phase::final_move: return final_move();
    case Phase::waiting: return waiting();
    case Phase::align_slave: return align_slave();
    case Phase::drive_homing: return drive_homing();
    case Phase::cam_seek: return cam_seek();
    case Phase::limit_reversal: return limit_reversal();
    case Phase::cam_stop: return cam_stop();
    case Phase::cam_latch: return cam_latch();
    case Phase::reference_check: return reference_check();
    case Phase::measure_travel: return measure_travel();
    case Phase::done:
      run.entered = true;
      return;
    case Phase::idle:
    case Phase::jog:
    case Phase::move:
    case Phase::stopping:
    case Phase::unlock:  // shown for a held axis only (AxisRun::shown_phase), never its own phase
    case Phase::lock:
    case Phase::return_to_start:  // after a failure (failure_policy.cpp), never a step's
      // Not a homing phase while a cycle runs: a bug. Stop rather than guess.
      return fail(AlarmCode::aborted);
  }
}

PhaseContext Engine::make_context(const Settings& settings, std::size_t axis, Alarms& alarms) {
  const int partner = gantry_partner(settings, axis);
  const auto p = static_cast<std::size_t>(partner);
  return PhaseContext{axes_[axis],
                      partner >= 0 ? &axes_[p] : nullptr,
                      inputs_[static_cast<std::size_t>(sensor_channel(settings, axis))],
                      partner >= 0 ? &inputs_[static_cast<std::size_t>(sensor_channel(settings, p))] : nullptr,
                      time_s_,
                      last_dt_s_,
                      alarms};
}

void Engine::begin_axis(const Settings& settings, std::size_t axis) {
  Alarms alarms(*this, settings);
  PhaseRunner(make_context(settings, axis, alarms), settings, axis).begin();
}

void Engine::run_axis(const Settings& settings, std::size_t axis) {
  // A phase change runs the next phase's entry in the same period, so no
  // period is lost between phases. Bounded: a period hands over a few times.
  Alarms alarms(*this, settings);
  for (int i = 0; i < 8; ++i) {
    PhaseRunner(make_context(settings, axis, alarms), settings, axis).dispatch();
    if (!cycle_runs(axis) || axes_[axis].entered) return;
  }
}

}  // namespace homing
