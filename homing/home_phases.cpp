// From the reference edge to home: the pull-off, the assignment of the home
// position and the final move.
#include "phase_runner.hpp"
#include "settings_check.hpp"

namespace homing {

double PhaseRunner::rest_offset_mm() const {
  // A commutator slave applies only its compensation on its own; the pull-off
  // is made by the pair together on the one output.
  if (commutator_slave()) return s.switch_compensation_mm;
  return s.pull_off_mm + (is_slave ? s.switch_compensation_mm : 0.0);
}

void PhaseRunner::pull_off() {
  if (entry()) {
    run.target_mm = run.reference_mm + away_from_reference() * rest_offset_mm();
    // The master holds where its braking left it, a little past its own
    // edge: the slave stands as far past its own, so the pull-off made
    // together leaves both at the same distance from their edges.
    if (commutator_slave()) run.target_mm += partner_run().motor.position_mm - partner_run().reference_mm;
  }
  move_to(run.target_mm, commutator_slave() ? latch_v : seek_v);
  if (!arrived()) return;
  if (commutator_slave()) return aligned();
  enter(row().after(Phase::pull_off));
}

void PhaseRunner::set_home(Run& r, std::size_t of_axis, double reference_motor_mm, double machine_mm_at_rest) {
  const double new_offset = machine_mm_at_rest - r.motor.position_mm;
  r.trigger_position_mm = reference_motor_mm + r.offset_mm;
  r.home_correction_mm = new_offset - r.offset_mm;
  r.offset_mm = new_offset;
  r.home = home_frame(settings.axes[of_axis]);
  r.reach(Reached::assigned);
  note_square();
}

// The moment both sides of a gantry are assigned their home, the pair stands
// square: each side at rest at its home position from its own sensor (switch
// compensation included). Locked from then on, it keeps this relative
// position; the next cycle counts its racking from here (gantry_guard.cpp).
void PhaseRunner::note_square() {
  if (partner < 0 || !run.has_reached(Reached::assigned) || !partner_run().has_reached(Reached::assigned)) return;
  Run& slave = is_slave ? run : partner_run();
  const Run& master = is_slave ? partner_run() : run;
  slave.pair_square_mm = slave.motor.position_mm - master.motor.position_mm;
}

void PhaseRunner::set_home(double reference_motor_mm, double machine_mm_at_rest) {
  set_home(run, axis, reference_motor_mm, machine_mm_at_rest);
}

void PhaseRunner::assign() {
  const Coordinate coordinate = row().coordinate;
  if (coordinate == Coordinate::here || coordinate == Coordinate::absolute_encoder) {
    const std::optional<double> here = run.coordinate_where_it_stands(s);
    if (!here) return fail(AlarmCode::encoder_fault);
    set_home(run.motor.position_mm, *here);
    return after_assign();
  }
  // A shared home/limit sensor must be left behind, or it trips at once.
  if (s.shared_limit && !commutator_slave() && active())
    return fail(AlarmCode::not_released, s.pull_off_mm);
  set_home(run.reference_mm, s.home_position_mm);
  if (commutator_master()) {
    // The slave motor rests at the same distance from its own edge.
    Run& sl = partner_run();
    const auto p = static_cast<std::size_t>(partner);
    set_home(sl, p, sl.reference_mm, settings.axes[p].home_position_mm);
  }
  after_assign();
}

void PhaseRunner::after_assign() {
  if (partner >= 0 && !is_slave && software_pair() && !partner_run().has_reached(Reached::assigned))
    return wait_for(Wait::partner_assigned, Phase::final_move);
  // The final move starts only with the slave locked to this axis, or the
  // slave would miss its first period and end apart from its master.
  if (partner >= 0 && !is_slave && !partner_run().follow_master)
    return wait_for(Wait::slave_locked, Phase::final_move);
  if (is_slave) {
    // A software-slaved slave rests on its own edge until the master has
    // its own: locking earlier would drag it along the master's back-off
    // and pull-off and undo the squaring.
    if (software_pair() && !partner_run().has_reached(Reached::assigned))
      return wait_for(Wait::partner_assigned, Phase::done);
    run.follow_master = true;
    return enter(Phase::done);
  }
  enter(Phase::final_move);
}

void PhaseRunner::final_move() {
  if (entry()) {
    if (!final_move_wanted(s)) return homed_at_rest();
    run.target_mm = s.final_position_mm - run.offset_mm;
  }
  move_to(run.target_mm, seek_v);
  if (arrived()) homed_at_rest();
}

void PhaseRunner::homed_at_rest() { enter(run.measuring ? Phase::measure_travel : Phase::done); }

}  // namespace homing
