// One axis in a homing cycle: how it begins (by its mode), which phase
// function runs, and the period loop that runs a new phase's entry at once.
#include "phase_runner.hpp"

namespace homing {

PhaseRunner::PhaseRunner(Engine& engine, const Settings& st, std::size_t a)
    : e(engine), settings(st), axis(a), run(engine.axes_[a]), s(st.axes[a]) {
  is_slave = gantry_master(st, a) >= 0;
  partner = gantry_partner(st, a);
  channel = e.sensor_channel(st, a);
  // The slave motor alone only corrects the gantry's skew (the gantry guard
  // stops it before the pair could rack beyond max_misalignment).
  if (commutator_slave()) s = commutator_slave_homing(s);
  dir = s.direction == Direction::positive ? 1.0 : -1.0;
  seek_v = mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min);
  latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
  accel = s.acceleration_mm_per_s2;
}

void PhaseRunner::begin() {
  run.entered = false;
  run.phase_start_mm = run.motor.position_mm;
  if (commutator_slave()) {
    run.follow_master = true;
    return wait_for(Wait::master_at_reference, Phase::align_slave);
  }
  switch (s.mode) {
    case HomingMode::disabled:
      run.homed = true;
      run.set_phase(Phase::done);
      return;
    case HomingMode::manual:
      set_home(run.motor.position_mm, s.home_position_mm);
      return enter(Phase::final_move);
    case HomingMode::absolute:
    case HomingMode::absolute_final: {
      if (!e.absolute_valid_[axis]) return fail(AlarmCode::encoder_fault);
      const double machine_now = e.absolute_mm_[axis] - s.home_position_mm;
      set_home(run.motor.position_mm, machine_now);
      return enter(Phase::final_move);
    }
    default:
      return enter(Phase::pre_move);
  }
}

void PhaseRunner::dispatch() {
  switch (run.phase) {
    case Phase::pre_move: return pre_move();
    case Phase::seek: return seek();
    case Phase::stop: return stop();
    case Phase::push: return push();
    case Phase::back_off: return back_off();
    case Phase::reapproach: return reapproach();
    case Phase::index: return index();
    case Phase::pull_off: return pull_off();
    case Phase::assign: return assign();
    case Phase::final_move: return final_move();
    case Phase::waiting: return waiting();
    case Phase::align_slave: return align_slave();
    case Phase::done:
      run.entered = true;
      return;
    case Phase::idle:
    case Phase::jog:
    case Phase::move:
    case Phase::stopping:
      // Not a homing phase while a cycle runs: a bug. Stop rather than guess.
      return fail(AlarmCode::aborted);
  }
}

void Engine::begin_axis(const Settings& settings, std::size_t axis) {
  PhaseRunner(*this, settings, axis).begin();
}

void Engine::run_axis(const Settings& settings, std::size_t axis) {
  // A phase change runs the next phase's entry in the same period, so no
  // period is lost between phases. Bounded: a period hands over a few times.
  for (int i = 0; i < 8; ++i) {
    PhaseRunner runner(*this, settings, axis);
    runner.dispatch();
    if (!cycle_active_ || !axes_[axis].in_cycle || axes_[axis].entered) return;
  }
}

}  // namespace homing
