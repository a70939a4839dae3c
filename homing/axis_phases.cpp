// One axis's homing phases: one small function per phase, an entry action on
// each phase change. Distances are motor positions (mm) unless named otherwise.
#include <algorithm>
#include <cmath>

#include "engine.hpp"
#include "gantry.hpp"
#include "settings_check.hpp"

namespace homing {

struct PhaseRunner {
  using Run = AxisRun;

  Engine& e;
  const Settings& settings;
  std::size_t axis;
  Run& run;
  AxisSettings s;             // the settings this axis homes with (a slave inherits its master's: gantry.hpp)
  int channel;                // input carrying this axis's home sensor
  int partner;                // gantry partner, -1 if none
  bool is_slave;
  double dir;                 // +1 / -1: toward the sensor
  double seek_v, latch_v, accel;

  PhaseRunner(Engine& engine, const Settings& st, std::size_t a)
      : e(engine), settings(st), axis(a), run(engine.axes_[a]), s(st.axes[a]) {
    is_slave = gantry_master(st, a) >= 0;
    partner = e.partner_of(st, a);
    channel = e.sensor_channel(st, a);
    dir = s.direction == Direction::positive ? 1.0 : -1.0;
    seek_v = mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min);
    latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
    accel = s.acceleration_mm_per_s2;
    if (commutator_slave()) {
      // The slave motor alone only corrects the gantry's skew, from its
      // master's reference edge: slowly (latch feedrate), on its switch edge
      // alone, and never further than the allowed misalignment (the gantry
      // guard stops it before the pair could rack beyond it).
      s.max_seek_travel_mm = s.max_misalignment_mm;
      s.pre_move_mode = PreMove::none;
      s.final_move_enable = false;
      if (mode_is_pushing(s.mode) || s.mode == HomingMode::switch_index)
        s.mode = mode_reapproaches(s.mode) ? HomingMode::switch_reapproach : HomingMode::switch_release;
      seek_v = latch_v;
    }
  }

  bool commutator_slave() const {
    return is_slave && settings.axes[axis].slave_mode == SlaveMode::external_commutator;
  }
  bool commutator_master() const {
    return partner >= 0 && !is_slave && is_commutator_slave(settings, static_cast<std::size_t>(partner));
  }
  bool software_pair() const {
    if (partner < 0) return false;
    const std::size_t slave = is_slave ? axis : static_cast<std::size_t>(partner);
    return settings.axes[slave].slave_mode == SlaveMode::own_output;
  }
  // The partner's home sensor (software-slaved pairs decide on both sensors).
  bool partner_active() const {
    return software_pair() && e.axes_[static_cast<std::size_t>(e.sensor_channel(settings, static_cast<std::size_t>(partner)))].sensor_active;
  }
  Run& partner_run() const { return e.axes_[static_cast<std::size_t>(partner)]; }
  const Engine::SensorEvent& event() const { return e.events_[static_cast<std::size_t>(channel)]; }
  bool active() const { return e.axes_[static_cast<std::size_t>(channel)].sensor_active; }
  bool edge_to(bool to_active) const { return event().edge && event().accepted.to_level == to_active; }
  double edge_mm() const { return event().accepted.position_mm; }
  double travelled() const { return std::abs(run.motor.position_mm - run.phase_start_mm); }
  bool at_rest() const { return run.motor.velocity_mm_per_s == 0; }
  bool arrived() const { return at_rest() && std::abs(run.motor.position_mm - run.target_mm) <= 1e-9; }
  double dt() const { return e.last_dt_s_; }

  void enter(Phase p) {
    run.set_phase(p);
    run.entered = false;
    run.phase_start_mm = run.motor.position_mm;
  }
  bool entry() {
    if (run.entered) return false;
    run.entered = true;
    return true;
  }
  void fail(AlarmCode code, double value = 0) {
    e.raise(settings, axis_bit(axis), Alarm{code, run.phase, AxisField::none, value, 0});
  }
  void move_to(double target_mm, double v) {
    run.target_mm = target_mm;
    run.command = move_to_command(run.motor, target_mm, v, accel, dt());
  }
  void wait_for(Wait w, Phase next) {
    enter(Phase::waiting);
    run.phase_data<phase_data::Waiting>() = {w, next};
  }

  // -- phases --------------------------------------------------------------

  void pre_move() {
    if (run.phase_data_if<phase_data::Clearing>()) return clear_sensors();
    if (entry()) {
      // A gantry decides for the pair: either side on its sensor counts.
      const bool needed = s.pre_move_mode == PreMove::always ||
                          (s.pre_move_mode == PreMove::if_sensor_active && (active() || partner_active()));
      if (!needed) return enter(Phase::seek);
      run.target_mm = run.motor.position_mm - dir * s.pre_move_distance_mm;
    }
    move_to(run.target_mm, seek_v);
    if (arrived()) enter(Phase::seek);
  }

  // A gantry with either side on its sensor at the start of the seek first
  // moves off both sensors together (latch feedrate, bounded by max_backoff),
  // then seeks: both sides meet their sensors within their skew, so the pair
  // cannot rack while one side seeks alone.
  void clear_sensors() {
    if (entry()) run.target_mm = run.motor.position_mm - dir * s.max_backoff_mm;
    if (!active() && !partner_active()) {
      enter(Phase::seek);
      run.phase_data<phase_data::Seek>().at_latch = true;
      return;
    }
    move_to(run.target_mm, latch_v);
    if (arrived()) fail(AlarmCode::not_released, travelled());
  }

  void seek() {
    if (entry()) {
      if (software_pair() && (active() || partner_active())) {
        enter(Phase::pre_move);
        run.phase_data<phase_data::Clearing>();
        return;
      }
      if (active()) {
        // Already on the sensor (MASSO): no seek, no stop; find the edge.
        run.reach(Reached::stopped_on_sensor);
        return after_stop();
      }
      // Bounded by max_seek_travel, braking in time to rest at its end.
      run.target_mm = run.phase_start_mm + dir * s.max_seek_travel_mm;
    }
    if (edge_to(true)) {
      const phase_data::Stop trigger{edge_mm(), dt()};
      enter(Phase::stop);
      run.phase_data<phase_data::Stop>() = trigger;
      return;
    }
    // Just off both sensors, the pair meets them again within the clearing
    // distance: at latch feedrate, so the side that meets its sensor first
    // does not stop much shorter than the other and rack the pair.
    const auto* seek = run.phase_data_if<phase_data::Seek>();
    move_to(run.target_mm, seek && seek->at_latch ? latch_v : seek_v);
    if (arrived()) {
      if (commutator_slave()) return fail(AlarmCode::misalignment, travelled());
      return fail(AlarmCode::sensor_not_found, travelled());
    }
  }

  void stop() {
    if (entry()) run.command = stop_command(accel);
    if (edge_to(false)) return fail(AlarmCode::overrun_during_stop);
    if (!at_rest()) return;
    // A release during the stop may still be in its debounce time when the
    // axis comes to rest: wait for the verdict, or back-off would take that
    // release (inside the stop) for its reference edge.
    const Debouncer& filter = e.sensor_filter_[static_cast<std::size_t>(channel)];
    if (filter.raw() != filter.stable()) return;
    // One control period of travel is allowed on top: the trigger cannot be
    // seen before the period in which it happened has ended. That is the
    // period the trigger was seen in (possibly a late one), not the current.
    const phase_data::Stop& trigger = run.phase_data<phase_data::Stop>();
    const double past = std::abs(run.motor.position_mm - trigger.trigger_mm);
    if (past > s.max_stop_distance_mm + seek_v * trigger.trigger_period_s + 1e-9)
      return fail(AlarmCode::stop_distance_exceeded, past);
    run.reach(Reached::stopped_on_sensor);
    after_stop();
  }

  void after_stop() {
    const Phase next = mode_is_pushing(s.mode) ? Phase::push : Phase::back_off;
    if (partner >= 0 && software_pair() && !partner_run().has_reached(Reached::stopped_on_sensor))
      return wait_for(Wait::partner_stopped, next);
    enter(next);
  }

  void push() {
    if (entry()) {
      run.push_output = true;
      run.target_mm = run.motor.position_mm + dir * s.push_distance_mm;
    }
    move_to(run.target_mm, latch_v);
    if (arrived()) {
      run.push_output = false;
      enter(Phase::back_off);
    }
  }

  void back_off() {
    if (entry()) run.target_mm = run.phase_start_mm - dir * s.max_backoff_mm;
    phase_data::BackOff& seen = run.phase_data<phase_data::BackOff>();
    if (event().index) {
      seen.index_seen = true;
      seen.index_seen_mm = event().index_mm;
    }
    if (edge_to(false)) {
      const double release_mm = edge_mm();
      run.reach(Reached::released);
      if (mode_reapproaches(s.mode)) {
        // A gantry turns back toward its sensors together, or one side would
        // run toward its sensor while the other still backs off.
        if (software_pair() && !partner_run().has_reached(Reached::released)) {
          run.command = stop_command(accel);
          return wait_for(Wait::partner_released, Phase::reapproach);
        }
        return enter(Phase::reapproach);
      }
      if (s.mode == HomingMode::switch_index) {
        // The release is accepted only after the debounce time: an index pulse
        // may already have passed beyond the release edge. It is the next one.
        if (seen.index_seen && beyond(release_mm, seen.index_seen_mm)) return reference_found(seen.index_seen_mm);
        enter(Phase::index);
        run.phase_data<phase_data::Index>().release_mm = release_mm;
        return;
      }
      return reference_found(release_mm);
    }
    move_to(run.target_mm, latch_v);
    if (arrived()) fail(AlarmCode::not_released, travelled());
  }

  void reapproach() {
    if (entry()) run.target_mm = run.phase_start_mm + dir * s.max_backoff_mm;
    if (edge_to(true)) return reference_found(edge_mm());
    move_to(run.target_mm, latch_v);
    if (arrived()) fail(AlarmCode::reapproach_not_found, s.max_backoff_mm);
  }

  // The index search runs away from the sensor (-dir) from the release edge.
  bool beyond(double release_mm, double x_mm) const { return (x_mm - release_mm) * -dir > 0; }

  void index() {
    if (entry()) run.target_mm = run.phase_start_mm - dir * index_search_mm(s);
    // A pulse in the same period but before the release edge is not the next one.
    const double release_mm = run.phase_data<phase_data::Index>().release_mm;
    if (event().index && beyond(release_mm, event().index_mm)) return reference_found(event().index_mm);
    move_to(run.target_mm, latch_v);
    if (arrived()) fail(AlarmCode::index_not_found, index_search_mm(s));
  }

  // The reference edge is located. A commutator master holds there (its
  // slave aligns on its own edge from this point); everyone else pulls off.
  void reference_found(double reference_mm) {
    run.reference_mm = reference_mm;
    run.reach(Reached::reference);
    if (commutator_master()) {
      run.command = stop_command(accel);
      return wait_for(Wait::slave_aligned, Phase::pull_off);
    }
    // A software gantry pulls off together: the side that found its edge
    // first holds there, or it would race ahead by a whole pull-off while
    // the other still backs off at latch feedrate.
    if (software_pair() && !partner_run().has_reached(Reached::reference)) {
      run.command = stop_command(accel);
      return wait_for(Wait::partner_at_reference, Phase::pull_off);
    }
    enter(Phase::pull_off);
  }

  double rest_offset_mm() const {
    // A commutator slave applies only its compensation on its own; the pull-off
    // is made by the pair together on the one output.
    if (commutator_slave()) return s.switch_compensation_mm;
    return s.pull_off_mm + (is_slave ? s.switch_compensation_mm : 0.0);
  }

  void pull_off() {
    if (entry()) {
      run.target_mm = run.reference_mm - dir * rest_offset_mm();
      // The master holds where its braking left it, a little past its own
      // edge: the slave stands as far past its own, so the pull-off made
      // together leaves both at the same distance from their edges.
      if (commutator_slave()) run.target_mm += partner_run().motor.position_mm - partner_run().reference_mm;
    }
    move_to(run.target_mm, commutator_slave() ? latch_v : seek_v);
    if (!arrived()) return;
    if (commutator_slave()) return aligned();
    enter(Phase::assign);
  }

  // Commutator slave: on its own edge (plus compensation). The output goes
  // back to the master (once this motor is at rest) and the pair pulls off
  // together; the master assigns both.
  void aligned() {
    run.aligning = false;
    run.reach(Reached::aligned);
    run.follow_master = true;
    run.command = stop_command(accel);
    wait_for(Wait::partner_assigned, Phase::done);
  }

  void set_home(Run& r, double reference_motor_mm, double machine_mm_at_rest) {
    const double new_offset = machine_mm_at_rest - r.motor.position_mm;
    r.trigger_position_mm = reference_motor_mm + r.offset_mm;
    r.home_correction_mm = new_offset - r.offset_mm;
    r.offset_mm = new_offset;
    r.homed = true;
    r.reach(Reached::assigned);
  }
  void set_home(double reference_motor_mm, double machine_mm_at_rest) {
    set_home(run, reference_motor_mm, machine_mm_at_rest);
  }

  void assign() {
    // A shared home/limit sensor must be left behind, or it trips at once.
    if (s.shared_limit && channel == static_cast<int>(axis) && active())
      return fail(AlarmCode::not_released, s.pull_off_mm);
    set_home(run.reference_mm, s.home_position_mm);
    if (commutator_master()) {
      // The slave motor rests at the same distance from its own edge.
      Run& sl = partner_run();
      set_home(sl, sl.reference_mm, settings.axes[static_cast<std::size_t>(partner)].home_position_mm);
    }
    after_assign();
  }

  void after_assign() {
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

  void final_move() {
    if (entry()) {
      if (!final_move_wanted(s)) return enter(Phase::done);
      run.target_mm = s.final_position_mm - run.offset_mm;
    }
    move_to(run.target_mm, seek_v);
    if (arrived()) enter(Phase::done);
  }

  void waiting() {
    run.entered = true;
    const Wait wait = run.waiting_for();
    if (wait == Wait::none) return;  // a later sequence step
    const Run& p = partner_run();
    bool ready = false;
    switch (wait) {
      case Wait::partner_stopped: ready = p.has_reached(Reached::stopped_on_sensor); break;
      case Wait::partner_assigned: ready = p.has_reached(Reached::assigned); break;
      case Wait::slave_aligned: ready = p.has_reached(Reached::aligned); break;
      case Wait::slave_locked: ready = p.follow_master; break;
      case Wait::partner_released: ready = p.has_reached(Reached::released) && at_rest(); break;
      case Wait::partner_at_reference: ready = p.has_reached(Reached::reference) && at_rest(); break;
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

  void align_slave() {
    // The master's output now drives only this motor, and this slave's
    // sensor is on the master's input: let the input settle for one period.
    if (entry()) {
      partner_run().commutator_output = true;
      e.filter_reset_[static_cast<std::size_t>(channel)] = true;
      run.command = stop_command(accel);
      return;
    }
    enter(Phase::seek);
  }

  void begin() {
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

  void dispatch() {
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
};

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
