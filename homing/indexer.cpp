// Locking indexers (axis.<a>.indexer_lock, README "Locking indexer"): the one
// place that decides whether an axis with one may move. It runs after every
// path that sets a motion command (homing phases, jog, move, final move,
// gantry follow), so whichever set it, the command of an axis that is not
// confirmed unlocked is replaced by a stop: nothing moves while locked.
#include "engine.hpp"

namespace homing {
namespace {

// The axis is in motion, or something wants it to move: a homing phase
// (not waiting for its step, not done), a jog, a move, a stop in progress.
bool wants_to_move(const AxisRun& run) {
  if (run.moving() || run.command.target_velocity_mm_per_s != 0) return true;
  switch (run.phase) {
    case Phase::jog:
    case Phase::move:
    case Phase::stopping: return true;
    default: break;
  }
  return run.in_cycle && run.phase != Phase::waiting && run.phase != Phase::done;
}

}  // namespace

void Engine::run_indexers(const Settings& settings, const Inputs& inputs) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    const AxisSettings& s = settings.axes[a];
    Indexer& ix = run.indexer;
    if (!s.indexer_lock) {
      ix = Indexer{};
      continue;
    }
    const bool unlocked_in = inputs.axes[a].indexer_unlocked;
    const double timeout_s = s.lock_timeout_ms / 1000.0;
    auto enter = [&](IndexerState st) {
      ix.state = st;
      ix.since_s = time_s_;
    };
    auto alarm = [&](AlarmCode code) {
      raise(settings, axis_bit(a), Alarm{code, Phase::idle, AxisField::lock_timeout_ms, s.lock_timeout_ms, 0});
    };
    // Switched on (or at start-up): the output is off, so the indexer locks.
    if (ix.state == IndexerState::none) enter(IndexerState::locking);
    const bool wants = wants_to_move(run);
    const bool at_rest = !wants;
    switch (ix.state) {
      case IndexerState::none:
      case IndexerState::locked:
        if (wants) enter(IndexerState::unlocking);
        break;
      case IndexerState::lock_failed:
        if (wants) enter(IndexerState::unlocking);
        else if (!unlocked_in) enter(IndexerState::locked);
        break;
      case IndexerState::locking:
        if (wants) enter(IndexerState::unlocking);
        else if (!unlocked_in) enter(IndexerState::locked);
        else if (time_s_ - ix.since_s > timeout_s) {
          alarm(AlarmCode::lock_not_confirmed);
          enter(IndexerState::lock_failed);
        }
        break;
      case IndexerState::unlocking:
      case IndexerState::unlocked:
        break;
    }
    // Unlocking and unlocked, also when just entered: the input of the period
    // just ended already shows a pin that never went in.
    if (ix.state == IndexerState::unlocking) {
      if (at_rest) enter(IndexerState::locking);  // the motion went away before the unlock
      else if (unlocked_in) enter(IndexerState::unlocked);
      else if (time_s_ - ix.since_s > timeout_s) alarm(AlarmCode::unlock_not_confirmed);
    } else if (ix.state == IndexerState::unlocked) {
      if (!unlocked_in) {
        // Locked under an axis meant to move: the motion stops (the alarm
        // halts every axis) and the command below holds this one. A motor
        // that was running loses its steps against the pin: the axis is no
        // longer where its coordinate says, whatever alarm_clears_homed says.
        if (run.moving() || run.period_start.velocity_mm_per_s != 0) run.home.reset();
        alarm(AlarmCode::lock_engaged);
        enter(IndexerState::unlocking);
      } else if (at_rest) {
        enter(IndexerState::locking);
      }
    }
    if (!ix.lets_move()) run.command = stop_command(s.acceleration_mm_per_s2);
  }
}

}  // namespace homing
