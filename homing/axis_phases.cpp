// One axis's homing phases: one small function per phase, an entry action on
// each phase change. Distances are motor positions (mm) unless named otherwise.
#include <algorithm>
#include <cmath>

#include "engine.hpp"
#include "settings_check.hpp"

namespace homing {

struct PhaseRunner {
  using Run = Engine::AxisRun;
  using Wait = Engine::AxisRun::Wait;

  Engine& e;
  const Settings& settings;
  std::size_t axis;
  Run& run;
  AxisSettings s;             // the settings this axis homes with (a commutator slave uses its master's)
  int channel;                // input carrying this axis's home sensor
  int partner;                // gantry partner, -1 if none
  bool is_slave;
  double dir;                 // +1 / -1: toward the sensor
  double seek_v, latch_v, accel;

  PhaseRunner(Engine& engine, const Settings& st, std::size_t a)
      : e(engine), settings(st), axis(a), run(engine.axes_[a]), s(st.axes[a]) {
    const int m = master_of(st.axes[a]);
    is_slave = m >= 0;
    partner = e.partner_of(st, a);
    if (is_slave && st.axes[a].slave_mode == SlaveMode::external_commutator) {
      const AxisSettings& own = st.axes[a];
      s = st.axes[static_cast<std::size_t>(m)];
      // The slave motor only corrects the gantry's skew: its search is bounded
      // by the pull-off plus the allowed misalignment.
      s.max_seek_travel_mm = s.pull_off_mm + own.max_misalignment_mm + s.max_stop_distance_mm;
      s.max_misalignment_mm = own.max_misalignment_mm;
      s.switch_compensation_mm = own.switch_compensation_mm;
      s.pre_move_mode = PreMove::none;
      s.home_position_mm = own.home_position_mm;
      s.final_move_enable = false;
      if (mode_is_pushing(s.mode))
        s.mode = mode_reapproaches(s.mode) ? HomingMode::switch_reapproach : HomingMode::switch_release;
    }
    channel = e.sensor_channel(st, a);
    dir = s.direction == Direction::positive ? 1.0 : -1.0;
    seek_v = mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min);
    latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
    accel = s.acceleration_mm_per_s2;
  }

  bool commutator_slave() const {
    return is_slave && settings.axes[axis].slave_mode == SlaveMode::external_commutator;
  }
  bool software_pair() const {
    if (partner < 0) return false;
    const std::size_t slave = is_slave ? axis : static_cast<std::size_t>(partner);
    return settings.axes[slave].slave_mode == SlaveMode::own_output;
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
    run.phase = p;
    run.entered = false;
    run.phase_start_mm = run.motor.position_mm;
  }
  bool entry() {
    if (run.entered) return false;
    run.entered = true;
    return true;
  }
  void fail(AlarmCode code, double value = 0) {
    e.raise(settings, axis, Alarm{code, run.phase, AxisField::none, value, 0});
  }
  void move_to(double target_mm, double v) {
    run.target_mm = target_mm;
    run.command = move_to_command(run.motor, target_mm, v, accel, dt());
  }
  void wait_for(Wait w, Phase next) {
    run.wait = w;
    run.next_phase = next;
    enter(Phase::waiting);
  }

  // -- phases --------------------------------------------------------------

  void pre_move() {
    if (entry()) {
      const bool needed = s.pre_move_mode == PreMove::always ||
                          (s.pre_move_mode == PreMove::if_sensor_active && active());
      if (!needed) return enter(Phase::seek);
      move_to(run.motor.position_mm - dir * s.pre_move_distance_mm, seek_v);
    }
    move_to(run.target_mm, seek_v);
    if (arrived()) enter(Phase::seek);
  }

  void seek() {
    if (entry()) {
      if (active()) {
        // Already on the sensor (MASSO): no seek, no stop; find the edge.
        run.triggered = true;
        run.trigger_mm = run.motor.position_mm;
        run.stopped_after_trigger = true;
        return after_stop();
      }
      run.command = velocity_command(dir * seek_v, accel);
      run.command.has_limit = true;
      run.command.limit_mm = run.phase_start_mm + dir * s.max_seek_travel_mm;
    }
    if (edge_to(true)) {
      run.triggered = true;
      run.trigger_mm = edge_mm();
      run.trigger_period_s = dt();
      if (partner >= 0 && software_pair()) {
        Run& p = partner_run();
        if (!p.triggered) {
          p.partner_marked = true;
          p.mark_mm = p.motor.position_mm;
        }
      }
      return enter(Phase::stop);
    }
    if (run.partner_marked && settings.axes[axis].slave_of != 0 &&
        std::abs(run.motor.position_mm - run.mark_mm) > settings.axes[axis].max_misalignment_mm)
      return fail(AlarmCode::misalignment, std::abs(run.motor.position_mm - run.mark_mm));
    if (run.partner_marked && !is_slave && partner >= 0) {
      const double limit = settings.axes[static_cast<std::size_t>(partner)].max_misalignment_mm;
      if (std::abs(run.motor.position_mm - run.mark_mm) > limit)
        return fail(AlarmCode::misalignment, std::abs(run.motor.position_mm - run.mark_mm));
    }
    if (travelled() >= s.max_seek_travel_mm - 1e-9) {
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
    const double past = std::abs(run.motor.position_mm - run.trigger_mm);
    if (past > s.max_stop_distance_mm + seek_v * run.trigger_period_s + 1e-9)
      return fail(AlarmCode::stop_distance_exceeded, past);
    run.stopped_after_trigger = true;
    after_stop();
  }

  void after_stop() {
    const Phase next = mode_is_pushing(s.mode) ? Phase::push : Phase::back_off;
    if (partner >= 0 && software_pair() && !partner_run().stopped_after_trigger)
      return wait_for(Wait::partner_stopped, next);
    enter(next);
  }

  void push() {
    if (entry()) {
      run.push_output = true;
      move_to(run.motor.position_mm + dir * s.push_distance_mm, latch_v);
    }
    move_to(run.target_mm, latch_v);
    if (arrived()) {
      run.push_output = false;
      enter(Phase::back_off);
    }
  }

  void back_off() {
    if (entry()) {
      run.command = velocity_command(-dir * latch_v, accel);
      run.command.has_limit = true;
      run.command.limit_mm = run.phase_start_mm - dir * s.max_backoff_mm;
      run.index_seen = false;
    }
    if (event().index) {
      run.index_seen = true;
      run.index_seen_mm = event().index_mm;
    }
    if (edge_to(false)) {
      run.release_mm = edge_mm();
      if (mode_reapproaches(s.mode)) return enter(Phase::reapproach);
      if (s.mode == HomingMode::switch_index) {
        // The release is accepted only after the debounce time: an index pulse
        // may already have passed beyond the release edge. It is the next one.
        if (run.index_seen && beyond_release(run.index_seen_mm)) {
          run.reference_mm = run.index_seen_mm;
          return enter(Phase::pull_off);
        }
        return enter(Phase::index);
      }
      run.reference_mm = run.release_mm;
      return enter(Phase::pull_off);
    }
    if (travelled() >= s.max_backoff_mm - 1e-9) fail(AlarmCode::not_released, travelled());
  }

  void reapproach() {
    if (entry()) {
      run.command = velocity_command(dir * latch_v, accel);
      run.command.has_limit = true;
      run.command.limit_mm = run.phase_start_mm + dir * s.max_backoff_mm;
    }
    if (edge_to(true)) {
      run.reference_mm = edge_mm();
      return enter(Phase::pull_off);
    }
    if (at_rest() && std::abs(run.motor.position_mm - run.command.limit_mm) <= 1e-9)
      fail(AlarmCode::reapproach_not_found, s.max_backoff_mm);
  }

  // The index search runs away from the sensor (-dir) from the release edge.
  bool beyond_release(double x_mm) const { return (x_mm - run.release_mm) * -dir > 0; }

  double index_bound() const { return s.index_pitch_mm * 1.1 + stop_distance_mm(latch_v, accel); }

  void index() {
    if (entry()) {
      run.command = velocity_command(-dir * latch_v, accel);
      run.command.has_limit = true;
      run.command.limit_mm = run.phase_start_mm - dir * index_bound();
    }
    // A pulse in the same period but before the release edge is not the next one.
    if (event().index && beyond_release(event().index_mm)) {
      run.reference_mm = event().index_mm;
      return enter(Phase::pull_off);
    }
    if (travelled() >= index_bound() - 1e-9) fail(AlarmCode::index_not_found, index_bound());
  }

  double rest_offset_mm() const {
    return s.pull_off_mm + (is_slave ? s.switch_compensation_mm : 0.0);
  }

  void pull_off() {
    if (entry()) {
      if (commutator_slave()) {
        const Run& m = partner_run();
        const double skew = (run.reference_mm - run.cycle_start_mm) - (m.reference_mm - m.cycle_start_mm);
        if (std::abs(skew) > settings.axes[axis].max_misalignment_mm)
          return fail(AlarmCode::misalignment, std::abs(skew));
      }
      run.target_mm = run.reference_mm - dir * rest_offset_mm();
    }
    move_to(run.target_mm, seek_v);
    if (arrived()) enter(Phase::assign);
  }

  void set_home(double reference_motor_mm, double machine_mm_at_rest) {
    const double new_offset = machine_mm_at_rest - run.motor.position_mm;
    run.trigger_position_mm = reference_motor_mm + run.offset_mm;
    run.home_correction_mm = new_offset - run.offset_mm;
    run.offset_mm = new_offset;
    run.homed = true;
    run.assigned = true;
  }

  void assign() {
    if (commutator_slave() && run.aligning) {
      // Alignment done: give the output back to the master.
      partner_run().commutator_output = false;
      e.filter_reset_[static_cast<std::size_t>(channel)] = true;
      run.aligning = false;
      run.slave_aligned = true;
    }
    set_home(run.reference_mm, s.home_position_mm);
    if (software_pair() && partner_run().assigned) {
      // Software-slaved squaring: both edges are measured from the same
      // start, so their difference is the gantry's skew.
      const std::size_t slave = is_slave ? axis : static_cast<std::size_t>(partner);
      const Run& sl = e.axes_[slave];
      const Run& m = e.axes_[is_slave ? static_cast<std::size_t>(partner) : axis];
      const double skew = (sl.reference_mm - sl.cycle_start_mm) - (m.reference_mm - m.cycle_start_mm);
      if (std::abs(skew) > settings.axes[slave].max_misalignment_mm) {
        e.raise(settings, slave, Alarm{AlarmCode::misalignment, e.axes_[slave].phase, AxisField::none,
                                       std::abs(skew), 0});
        return;
      }
    }
    after_assign();
  }

  void after_assign() {
    if (partner >= 0 && !is_slave) {
      const Run& p = partner_run();
      const bool ready = software_pair() ? p.assigned : p.slave_aligned;
      if (!ready) return wait_for(software_pair() ? Wait::partner_assigned : Wait::slave_aligned, Phase::final_move);
    }
    if (is_slave) {
      // A software-slaved slave rests on its own edge until the master has
      // its own: locking earlier would drag it along the master's back-off
      // and pull-off and undo the squaring.
      if (software_pair() && !partner_run().assigned) return wait_for(Wait::partner_assigned, Phase::done);
      run.follow_master = true;
      return enter(Phase::done);
    }
    enter(Phase::final_move);
  }

  void final_move() {
    const bool wanted = s.mode == HomingMode::absolute_final ||
                        (s.final_move_enable && s.mode != HomingMode::absolute &&
                         s.mode != HomingMode::disabled);
    if (entry()) {
      if (!wanted) return enter(Phase::done);
      run.target_mm = s.final_position_mm - run.offset_mm;
    }
    move_to(run.target_mm, seek_v);
    if (arrived()) enter(Phase::done);
  }

  void waiting() {
    run.entered = true;
    if (run.wait == Wait::none) return;  // a later sequence step
    if (run.follow_master && !run.aligning) {
      // Commutator slave: moves with the master until the master has its edge.
      const Run& m = partner_run();
      if (commutator_slave() && m.assigned) {
        run.follow_master = false;
        run.aligning = true;
        run.wait = Wait::none;
        return enter(Phase::align_slave);
      }
      return;
    }
    const Run& p = partner_run();
    bool ready = false;
    switch (run.wait) {
      case Wait::partner_stopped: ready = p.stopped_after_trigger; break;
      case Wait::partner_assigned: ready = p.assigned; break;
      case Wait::slave_aligned: ready = p.slave_aligned; break;
      case Wait::none: break;
    }
    if (ready) {
      run.wait = Wait::none;
      if (is_slave && run.next_phase == Phase::done) run.follow_master = true;  // now lock
      enter(run.next_phase);
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
    run.triggered = false;
    run.stopped_after_trigger = false;
    enter(Phase::seek);
  }

  void begin() {
    run.entered = false;
    run.phase_start_mm = run.motor.position_mm;
    if (commutator_slave()) {
      run.follow_master = true;
      run.wait = Wait::slave_aligned;  // any value but none: this slave is active
      run.phase = Phase::waiting;
      return;
    }
    switch (s.mode) {
      case HomingMode::disabled:
        run.homed = true;
        run.phase = Phase::done;
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
