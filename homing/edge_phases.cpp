// Locating the reference edge: the back-off to the release edge, the
// re-approach to the trigger edge, or the search for the next index pulse.
#include "phase_runner.hpp"
#include "settings_check.hpp"

namespace homing {

void PhaseRunner::back_off() {
  if (entry()) run.target_mm = run.phase_start_mm - dir * s.max_backoff_mm;
  phase_data::BackOff& seen = run.phase_data<phase_data::BackOff>();
  if (event().index) {
    seen.index_seen = true;
    seen.index_seen_mm = event().index_mm;
  }
  if (edge_to(false)) {
    const double release_mm = edge_mm();
    if (!run.edges.release_seen) {
      run.edges.release_seen = true;
      run.edges.release_mm = release_mm;
    }
    ++run.edges.releases;
    run.reach(Reached::released);
    const Phase next = row().after(Phase::back_off);
    if (next == Phase::reapproach) {
      // A gantry turns back toward its sensors together, or one side would
      // run toward its sensor while the other still backs off: each side
      // brakes at its release, and both start from rest in one period.
      if (software_pair()) {
        run.command = stop_command(accel);
        return wait_for(Wait::partner_released, Phase::reapproach);
      }
      return enter(Phase::reapproach);
    }
    if (next == Phase::index) {
      // The release is accepted only after the debounce time: an index pulse
      // may already have passed beyond the release edge. It is the next one.
      if (seen.index_seen && beyond(release_mm, seen.index_seen_mm)) {
        note_index(release_mm, seen.index_seen_mm);
        return reference_found(seen.index_seen_mm);
      }
      enter(Phase::index);
      run.phase_data<phase_data::Index>().release_mm = release_mm;
      return;
    }
    return reference_found(release_mm);
  }
  move_to(run.target_mm, latch_v);
  if (arrived()) fail(AlarmCode::not_released, travelled());
}

void PhaseRunner::reapproach() {
  if (entry()) run.target_mm = run.phase_start_mm + dir * s.max_backoff_mm;
  if (edge_to(true)) return latch_edge_found(edge_mm());
  move_to(run.target_mm, latch_v);
  if (arrived()) fail(AlarmCode::reapproach_not_found, s.max_backoff_mm);
}

// One slow approach found the edge. With several latch passes the axis backs
// off to the release and approaches again until it has them all; the
// reference is their median, refused when they disagree beyond the limit.
void PhaseRunner::latch_edge_found(double edge_mm) {
  run.latch.add(edge_mm);
  const int passes = latch_passes_of(s.latch_passes);
  if (run.latch.count < passes) {
    // A gantry backs off again together, as from its reference edge.
    if (software_pair()) {
      run.command = stop_command(accel);
      return wait_for(Wait::partner_latched, Phase::back_off);
    }
    return enter(Phase::back_off);
  }
  const EdgeStats st = edge_stats(run.latch.edges());
  run.health.latch_passes = run.latch.count;
  run.health.latch_spread_mm = st.spread_mm;
  run.health.latch_sigma_mm = st.sigma_mm;
  if (passes > 1 && st.spread_mm > s.max_latch_spread_mm) return fail(AlarmCode::switch_not_repeatable, st.spread_mm);
  reference_found(st.median_mm);
}

void PhaseRunner::index() {
  if (entry()) run.target_mm = run.phase_start_mm - dir * index_search_mm(s);
  // A pulse in the same period but before the release edge is not the next one.
  const double release_mm = run.phase_data<phase_data::Index>().release_mm;
  if (event().index && beyond(release_mm, event().index_mm)) {
    note_index(release_mm, event().index_mm);
    return reference_found(event().index_mm);
  }
  move_to(run.target_mm, latch_v);
  if (arrived()) fail(AlarmCode::index_not_found, index_search_mm(s));
}

// How far the index pulse taken lies from the switch edge it was searched from.
void PhaseRunner::note_index(double release_mm, double index_mm) {
  run.health.index_distance_mm = std::abs(index_mm - release_mm);
  run.health.index_near_edge = index_near_edge(run.health.index_distance_mm, s.index_pitch_mm);
}

// Both sides of a gantry found their edges: how far apart they lie, each
// from where its side stood when the pair was last square (where this cycle
// found it, unless an alarm left it racked), is how far out of square with
// its sensors the pair stood (docs/health.md "Gantry skew"). The
// compensation comes later, in the pull-off; published on the slave.
void PhaseRunner::note_gantry_skew() {
  Run& slave = is_slave ? run : partner_run();
  const Run& master = is_slave ? partner_run() : run;
  slave.health.gantry_skew_mm =
      (slave.reference_mm - master.reference_mm) - slave.pair_square_mm.value_or(slave.pair_rel0_mm);
  slave.health.gantry_skew_measured = true;
}

// The reference edge is located. A commutator master holds there (its
// slave aligns on its own edge from this point); everyone else pulls off.
void PhaseRunner::reference_found(double reference_mm) {
  run.reference_mm = reference_mm;
  measure_switch(run.health, run.edges, run.latch, dir, ctx.input.filter.transitions(), ctx.input.filter.accepted());
  run.reach(Reached::reference);
  if (partner >= 0 && partner_run().has_reached(Reached::reference)) note_gantry_skew();
  if (commutator_master()) {
    run.command = stop_command(accel);
    return wait_for(Wait::slave_aligned, Phase::pull_off);
  }
  // A software gantry pulls off together: each side holds at its edge, and
  // both start from rest in one period. The side first at its edge would
  // otherwise race ahead by a whole pull-off while the other still backs
  // off at latch feedrate, and the side last at its edge would run on into
  // its pull-off while the first still brakes (campaign seed 195009253).
  if (software_pair()) {
    run.command = stop_command(accel);
    return wait_for(Wait::partner_at_reference, Phase::pull_off);
  }
  enter(Phase::pull_off);
}

}  // namespace homing
