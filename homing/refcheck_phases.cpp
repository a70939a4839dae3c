// The reference check (trust.hpp): after a restart, an axis whose last stop
// was clean finds its switch edge at latch feedrate near where its stored
// position puts it, instead of a full cycle. The edge is the one its method
// homes on, crossed the same way: the trigger edge approaching from the side
// the axis rests on, or the release edge backing off again. Accepted within
// refcheck_tolerance: the axis is homed there, its coordinate set by the
// edge found. Refused beyond: it stays unhomed and a full cycle is needed.
// Either way the figure is kept (refcheck_error) and the axis goes back
// where it started. Every step is bounded in distance: no further than
// refcheck_tolerance plus max_stop_distance past the expected edge (the room
// a seek may take past a trigger; a release method's approach max_backoff
// more, for its trigger lies the hysteresis beyond), max_backoff off the switch. A home cam
// lies in mid-travel, so a homed axis may rest on its far side (a final move
// or a jog across it), and so may one past a home switch that is a short
// flag: the check first goes back across the cam or flag to the rest point
// its stored position gives, as far as that position says.
#include <algorithm>
#include <cmath>

#include "phase_runner.hpp"

namespace homing {

using Step = phase_data::RefCheck::Step;

namespace {

// How far past the expected edge an approach looks for its trigger: the
// tolerance, the room a seek takes past a trigger, the travel while the
// debounce time accepts the edge; for a release method also the switch's
// hysteresis, by which its trigger lies beyond the release edge it checks:
// less than max_backoff, or no cycle could have released it (campaign seeds
// 187201697, 187209246: hysteresis 0.14 mm beyond a bound of 0.12 mm, an
// unmoved axis refused).
double approach_past_mm(const AxisSettings& s, double latch_v, RefcheckEdge edge) {
  return s.refcheck_tolerance_mm + s.max_stop_distance_mm + latch_v * s.debounce_ms / 1000.0 +
         (edge == RefcheckEdge::release ? s.max_backoff_mm : 0.0);
}

}  // namespace

void PhaseRunner::reference_check() {
  auto& c = run.phase_data<phase_data::RefCheck>();
  if (entry()) refcheck_begin(c);
  switch (c.step) {
    case Step::cross_cam: return refcheck_cross_cam(c);
    case Step::leave_sensor: return refcheck_leave_sensor(c);
    case Step::approach: return refcheck_approach(c);
    case Step::back_off: return refcheck_back_off(c);
    case Step::go_back: return refcheck_go_back(c);
    case Step::release: return refcheck_release(c);
  }
}

// The edge lies where the frame puts it: the rest point (home_position)
// lies pull-off away from it.
void PhaseRunner::refcheck_begin(phase_data::RefCheck& c) {
  c.start_mm = run.motor.position_mm;
  c.expected_mm = s.home_position_mm - away_from_reference() * rest_offset_mm() - run.offset_mm;
  c.started_on_sensor = active();
  if (c.started_on_sensor) {
    // A final move or a jog may have left the axis deeper on its switch (or
    // its home cam) than max_backoff (campaign seed 187105905: 2 mm on it,
    // max_backoff 2.8, moved 3.9 mm further): it backs off as far as its
    // stored position puts the edge, and max_backoff beyond.
    const double away = away_from_reference();
    const double target = away * std::max(away * c.start_mm + s.max_backoff_mm, away * c.expected_mm + s.max_backoff_mm);
    return refcheck_step(c, Step::leave_sensor, target);
  }
  // Past the edge by the tolerance, the room a seek takes past a trigger,
  // the travel while the debounce time accepts the edge (approach_past_mm).
  const double approach = c.expected_mm - away_from_reference() * approach_past_mm(s, latch_v, refcheck_edge(row()));
  // Past the edge by more than the tolerance, and off the switch: it stands
  // on the far side of its switch or cam, where a move took it. A home cam
  // lies in mid-travel (campaign seed 187000328: a final move across the
  // cam, refused with the cam's width as its mismatch), and so does a home
  // switch that is a short flag under a proximity sensor (campaign seed
  // 993609: a final move past the flag, refused at once, or searched for
  // further away from it). Back across it to the rest point, as far as the
  // stored position says, and the check from there. A switch that runs on
  // to the end of the travel would read active there: a carriage off it is
  // not where it was stored, and the approach from the rest point finds the
  // edge as far off as it was moved.
  if ((c.start_mm - c.expected_mm) * away_from_reference() < -s.refcheck_tolerance_mm)
    return refcheck_step(c, Step::cross_cam, c.expected_mm + away_from_reference() * rest_offset_mm());
  refcheck_step(c, Step::approach, approach);
}

// The way the move that left it there came, at seek feedrate, the cam's
// edges crossed on the way taken for nothing; then the check as from a
// cycle's rest point (on the cam there: off it first).
void PhaseRunner::refcheck_cross_cam(phase_data::RefCheck& c) {
  move_to(run.target_mm, seek_v);
  if (!arrived()) return;
  if (active()) return refcheck_step(c, Step::leave_sensor, run.motor.position_mm + away_from_reference() * s.max_backoff_mm);
  refcheck_step(c, Step::approach, c.expected_mm - away_from_reference() * approach_past_mm(s, latch_v, refcheck_edge(row())));
}

void PhaseRunner::refcheck_step(phase_data::RefCheck& c, phase_data::RefCheck::Step step, double target_mm) {
  c.step = step;
  run.target_mm = target_mm;
  run.phase_start_mm = run.motor.position_mm;
}

// Started on the switch (stored there, or moved onto it): its release edge
// is the reference of a release method; a trigger method approaches again.
void PhaseRunner::refcheck_leave_sensor(phase_data::RefCheck& c) {
  if (edge_to(false)) {
    if (refcheck_edge(row()) == RefcheckEdge::release) return refcheck_judge(c, edge_mm(), true);
    return refcheck_step(c, Step::approach,
                         c.expected_mm - away_from_reference() * approach_past_mm(s, latch_v, RefcheckEdge::trigger));
  }
  move_to(run.target_mm, latch_v);
  if (arrived()) refcheck_judge(c, run.motor.position_mm, false);
}

void PhaseRunner::refcheck_approach(phase_data::RefCheck& c) {
  if (edge_to(true)) {
    if (refcheck_edge(row()) == RefcheckEdge::trigger) return refcheck_judge(c, edge_mm(), true);
    c.trigger_mm = edge_mm();
    return refcheck_step(c, Step::back_off, edge_mm() + away_from_reference() * s.max_backoff_mm);
  }
  move_to(run.target_mm, latch_v);
  if (arrived()) refcheck_judge(c, run.motor.position_mm, false);
}

void PhaseRunner::refcheck_back_off(phase_data::RefCheck& c) {
  if (edge_to(false)) return refcheck_judge(c, edge_mm(), true);
  move_to(run.target_mm, latch_v);
  // Met the switch but it never released: its trigger is the only figure.
  if (arrived()) refcheck_judge(c, c.trigger_mm, false);
}

// found: the reference edge at edge_mm; else edge_mm is as far as the search
// went without it, and the figure says at least how far off it is. Refused,
// the stored position is no longer offered at once (trust unknown).
void PhaseRunner::refcheck_judge(phase_data::RefCheck& c, double edge_mm, bool found) {
  const double error = edge_mm - c.expected_mm;
  run.refcheck_error_mm = error;
  c.accepted = found && std::abs(error) <= s.refcheck_tolerance_mm;
  double back_mm = c.start_mm;
  if (c.accepted) {
    c.offset_mm = run.offset_mm - error;
    run.trigger_position_mm = edge_mm + run.offset_mm;
    run.home_correction_mm = -error;
    // Homed resting on its switch, a shared limit would trip at once: end
    // where a cycle ends, pull-off away from the edge. So too a shared limit
    // that started nearer its edge than that: back there, the switch's
    // hysteresis may hold it active after the approach triggered it
    // (campaign seed 187208768: a trigger method jogged off its tripped
    // sensor just until it released).
    const bool near = (c.start_mm - edge_mm) * away_from_reference() < rest_offset_mm();
    if (c.started_on_sensor || (s.shared_limit && near)) back_mm = edge_mm + away_from_reference() * rest_offset_mm();
  } else {
    run.restored.reset();
  }
  refcheck_step(c, Step::go_back, back_mm);
}

// Back at seek feedrate, as a pull-off: the path was just travelled. Homed
// only at rest there, off the switch it was checked on.
void PhaseRunner::refcheck_go_back(phase_data::RefCheck& c) {
  move_to(run.target_mm, seek_v);
  if (!arrived()) return;
  // A shared limit the approach triggered may still be held active there by
  // the switch's hysteresis (it grew since the cycle, or the cycle's noise
  // let it release nearer): homed on it, it would trip hard_limit at once
  // (campaign seed 194072538). Off it at latch feedrate first.
  if (c.accepted && !c.released && s.shared_limit && !commutator_slave() && active())
    return refcheck_step(c, Step::release, run.motor.position_mm + away_from_reference() * s.max_backoff_mm);
  if (c.accepted) {
    run.offset_mm = c.offset_mm;
    run.home = home_frame(settings.axes[axis]);
    run.homed_by_check = true;
    run.restored.reset();
    run.reach(Reached::assigned);
  }
  enter(Phase::done);
}

// Released: pull-off beyond that release edge, where a cycle would have
// come to rest had the switch released there. Not within max_backoff: the
// switch holds on (not_released, as a cycle's back-off says it).
void PhaseRunner::refcheck_release(phase_data::RefCheck& c) {
  if (edge_to(false)) {
    c.released = true;
    return refcheck_step(c, Step::go_back, edge_mm() + away_from_reference() * rest_offset_mm());
  }
  move_to(run.target_mm, latch_v);
  if (arrived()) fail(AlarmCode::not_released, s.max_backoff_mm);
}

}  // namespace homing
