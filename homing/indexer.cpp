// Locking indexers (axis.<a>.indexer_lock, docs/homing-methods.md "Locking indexer"): the one
// place that decides whether an axis with one may move. It runs after every
// path that sets a motion command (homing phases, jog, move, final move,
// gantry follow), so whichever set it, the command of an axis that is not
// confirmed unlocked is replaced by a stop: nothing moves while locked.
#include <cmath>

#include "engine.hpp"
#include "settings_check.hpp"

namespace homing {
namespace {

// The axis is in motion, or something wants it to move: a homing phase
// (not waiting for its step, not done), a jog, a move, a stop in progress.
// What keeps an unlocked indexer unlocked.
bool wants_to_move(const AxisRun& run) {
  if (run.moving() || run.command.target_velocity_mm_per_s != 0) return true;
  switch (run.phase) {
    case Phase::jog:
    case Phase::move:
    case Phase::stopping: return true;
    default: break;
  }
  // (An axis back at its start after a failed cycle rests idle in it: failure_policy.cpp.)
  return run.in_cycle && run.phase != Phase::waiting && run.phase != Phase::done && run.phase != Phase::idle;
}

// What unlocks a locked one: as wants_to_move(), less the cycle's phases
// that move nothing, assigning the coordinate and a final move with no
// length (manual or absolute_final standing at final_position). A cycle that
// starts with them, or an axis whose sequence step begins in the period
// another's ends, would otherwise pull the pin for one period for nothing.
// Mid-cycle they keep an unlocked indexer unlocked (wants_to_move()): the
// motion before and after them is one.
bool has_motion_to_do(const AxisRun& run, const AxisSettings& s) {
  if (!wants_to_move(run)) return false;
  if (run.moving() || run.command.target_velocity_mm_per_s != 0) return true;
  switch (run.phase) {
    case Phase::assign: return false;
    case Phase::final_move:
      return final_move_wanted(s) &&
             std::abs(s.final_position_mm - run.offset_mm - run.motor.position_mm) > kArrivedMm;
    default: return true;
  }
}

// One period of one indexer: what it sees, and what it asks of the engine.
struct IndexerPeriod {
  Indexer& ix;
  bool unlocked_in;  // the indexer reports its pin out (the period just ended)
  bool wants;        // the axis moves or is to move: an unlocked indexer stays unlocked
  bool needs;        // the axis has motion to do now: a locked (or locking) indexer unlocks
  double now_s;
  double timeout_s;
  AlarmCode alarm = AlarmCode::none;
  IndexerState after_alarm{};  // entered once the alarm is raised (it names the phase it struck in)
  bool steps_lost = false;     // a running motor met the pin

  void enter(IndexerState st) {
    ix.state = st;
    ix.since_s = now_s;
  }
  bool timed_out() const { return now_s - ix.since_s > timeout_s; }
  void raise(AlarmCode code, IndexerState then) {
    alarm = code;
    after_alarm = then;
  }

  // Locked: a motion to come raises the unlock output first.
  void locked() {
    if (needs) enter(IndexerState::unlocking);
  }
  // Unlock output on, motion held: on until the pin is reported out.
  void unlocking() {
    if (!wants) enter(IndexerState::locking);  // the motion went away before the unlock
    else if (unlocked_in) enter(IndexerState::unlocked);
    else if (timed_out()) raise(AlarmCode::unlock_not_confirmed, IndexerState::unlocking);
  }
  // Unlocked for motion: locked again once at rest; reported locked before
  // that, the pin went in on its own.
  void unlocked(bool motor_ran) {
    if (!unlocked_in) {
      steps_lost = motor_ran;
      raise(AlarmCode::lock_engaged, IndexerState::unlocking);  // held; at rest it locks (output off)
    } else if (!wants) {
      enter(IndexerState::locking);
    }
  }
  // At rest, unlock output off: locked once the pin is reported in.
  void locking() {
    if (needs) enter(IndexerState::unlocking);
    else if (!unlocked_in) enter(IndexerState::locked);
    else if (timed_out()) raise(AlarmCode::lock_not_confirmed, IndexerState::lock_failed);
  }
  // The lock timed out (alarm raised once): locked when the pin is seen in.
  void lock_failed() {
    if (needs) enter(IndexerState::unlocking);
    else if (!unlocked_in) enter(IndexerState::locked);
  }

  void run(bool motor_ran) {
    switch (ix.state) {
      case IndexerState::none:
        return enter(IndexerState::locking);  // switched on, or start-up: the output is off
      case IndexerState::locked: return locked();
      case IndexerState::unlocking: return unlocking();
      case IndexerState::unlocked: return unlocked(motor_ran);
      case IndexerState::locking: return locking();
      case IndexerState::lock_failed: return lock_failed();
    }
  }
};

}  // namespace

void Engine::run_indexers(const Settings& settings, const Inputs& inputs) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    AxisRun& run = axes_[a];
    const AxisSettings& s = settings.axes[a];
    if (!s.indexer_lock) {
      run.indexer = Indexer{};
      continue;
    }
    IndexerPeriod p{run.indexer, inputs.axes[a].indexer_unlocked, wants_to_move(run), has_motion_to_do(run, s),
                    time_s_, s.lock_timeout_ms / 1000.0};
    const bool motor_ran = run.moving() || run.period_start.velocity_mm_per_s != 0;
    // A state entered now acts on this period's input at once (a pin already
    // out, or already in): at most a few hand-overs, the first alarm ends it.
    for (int i = 0; i < 3 && p.alarm == AlarmCode::none; ++i) {
      const IndexerState before = run.indexer.state;
      p.run(motor_ran);
      if (run.indexer.state == before) break;
    }
    // The motor ran on against the pin: the axis is no longer where its
    // coordinate says, whatever alarm_clears_homed says.
    if (p.steps_lost) run.lose_reference();
    if (p.alarm != AlarmCode::none) {
      raise(settings, axis_bit(a), Alarm{p.alarm, Phase::idle, AxisField::lock_timeout_ms, s.lock_timeout_ms, 0});
      if (run.indexer.state != p.after_alarm) p.enter(p.after_alarm);
    }
    if (!run.indexer.lets_move()) run.command = stop_command(s.acceleration_mm_per_s2);
  }
}

}  // namespace homing
