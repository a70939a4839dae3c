// A gantry homes as a pair: one side waits for the other, and a commutator
// slave finds its own edge alone on its master's output.
#include "mutation.hpp"
#include "phase_runner.hpp"

namespace homing {

// Commutator slave: on its own edge (plus compensation). The output goes
// back to the master (once this motor is at rest) and the pair pulls off
// together; the master assigns both.
void PhaseRunner::aligned() {
  run.aligning = false;
  run.reach(Reached::aligned);
  run.follow_master = true;
  run.command = stop_command(accel);
  wait_for(Wait::partner_assigned, Phase::done);
}

void PhaseRunner::waiting() {
  run.entered = true;
  const Wait wait = run.waiting_for();
  if (wait == Wait::none) return;  // a later sequence step
  const Run& p = partner_run();
  bool ready = false;
  switch (wait) {
    case Wait::partner_stopped: ready = p.has_reached(Reached::stopped_on_sensor) && hand_over_ready(); break;
    case Wait::partner_assigned: ready = p.has_reached(Reached::assigned); break;
    case Wait::slave_aligned: ready = p.has_reached(Reached::aligned); break;
    case Wait::slave_locked: ready = p.follow_master; break;
    // A latch pass waits for the partner's edge of the same pass, not an earlier one.
    case Wait::partner_released:
      ready = p.has_reached(Reached::released) && p.edges.releases >= run.edges.releases && hand_over_ready();
      break;
    case Wait::partner_latched:
      ready = p.has_reached(Reached::released) && p.latch.count >= run.latch.count && hand_over_ready();
      break;
    case Wait::partner_at_reference: ready = p.has_reached(Reached::reference) && hand_over_ready(); break;
    case Wait::master_at_reference:
      // Commutator slave: moves with the master until the master holds,
      // at rest, on its reference edge.
      ready = p.waiting_for() == Wait::slave_aligned && p.motor.velocity_mm_per_s == 0 && at_rest();
      if (ready) {
        run.follow_master = false;
        run.aligning = true;
      }
      break;
    case Wait::none: break;
  }
  if (ready) {
    const Phase next = run.phase_data<phase_data::Waiting>().next;
    if (is_slave && next == Phase::done) run.follow_master = true;  // now lock
    enter(next);
  }
}

// Both sides of a software gantry start the next phase from rest, in the
// same period: each has waited at rest since an earlier period, or the
// partner has already gone on in this period. A side that arrives in this
// period waits one more: the side stepped before it in this period looked
// before it arrived, and both then go in the next (the motors integrate
// their new commands only in the next period anyway).
bool PhaseRunner::hand_over_ready() const {
  const auto rested_before = [this](const Run& r, bool self) {
    const auto* w = r.phase_data_if<phase_data::Waiting>();
    return r.motor.velocity_mm_per_s == 0 && w &&
           (w->since_s < ctx.time_s || (self && planted(Mutant::gantry_side_turns_alone)));
  };
  const Run& p = partner_run();
  return rested_before(run, true) && (p.phase != Phase::waiting || rested_before(p, false));
}

void PhaseRunner::align_slave() {
  // The master's output now drives only this motor, and this slave's
  // sensor is on the master's input: let the input settle, for this
  // slave's debounce time at least. The slave rode with its master and may
  // have left its own edge just before: a switch still bouncing when the
  // input was taken over would otherwise be taken at a bounce's level, and
  // its true edge lost (campaign seed 8001884).
  if (entry()) {
    partner_run().commutator_output = true;
    ctx.input.reset = true;
    run.command = stop_command(accel);
    return;
  }
  const Debouncer& filter = ctx.input.filter;
  if (filter.raw() != filter.stable() || ctx.time_s - filter.last_change_s() + 1e-9 < s.debounce_ms / 1000.0) return;
  enter(Phase::seek);
}

}  // namespace homing
