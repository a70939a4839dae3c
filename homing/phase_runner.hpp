#pragma once
// Runs one axis's homing phases for one period: one small function per
// phase, an entry action on each phase change. Distances are motor
// positions (mm) unless named otherwise. Internal to the engine: the phases
// see only their context (this axis, its gantry partner, the input carrying
// its sensor, the time, the alarm path), never the engine itself.
#include <cmath>
#include <optional>

#include "alarm_sink.hpp"
#include "axis_run.hpp"
#include "gantry.hpp"
#include "input_channel.hpp"
#include "settings.hpp"

namespace homing {

// What one axis's phases may see and change in one period.
struct PhaseContext {
  AxisRun& run;
  AxisRun* partner_run;                 // the gantry partner, nullptr if none
  InputChannel& input;                  // the input carrying this axis's home sensor
  const InputChannel* partner_input;    // the partner's, nullptr if none
  double time_s;                        // engine time now
  double dt_s;                          // length of the period that just ended
  AlarmSink& alarms;
};

struct PhaseRunner {
  using Run = AxisRun;

  PhaseContext ctx;
  const Settings& settings;
  std::size_t axis;
  Run& run;
  AxisSettings s;             // the settings this axis homes with (a slave inherits its master's: gantry.hpp)
  int partner;                // gantry partner, -1 if none
  bool is_slave;
  double dir;                 // +1 / -1: toward the sensor
  double seek_v, latch_v, accel;

  PhaseRunner(const PhaseContext& context, const Settings& st, std::size_t a);  // axis_phases.cpp

  // What this axis's homing method does (modes.hpp).
  const ModeRow& row() const { return mode_row(s.mode); }
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
  bool partner_active() const { return software_pair() && ctx.partner_input && ctx.partner_input->sensor_active; }
  Run& partner_run() const { return *ctx.partner_run; }
  bool hand_over_ready() const;
  const SensorEvent& event() const { return ctx.input.event; }
  bool active() const { return ctx.input.sensor_active; }
  bool edge_to(bool to_active) const { return event().edge && event().accepted.to_level == to_active; }
  double edge_mm() const { return event().accepted.position_mm; }
  double travelled() const { return std::abs(run.motor.position_mm - run.phase_start_mm); }
  bool at_rest() const { return run.motor.velocity_mm_per_s == 0; }
  bool arrived() const { return at_rest() && std::abs(run.motor.position_mm - run.target_mm) <= kArrivedMm; }
  double dt() const { return ctx.dt_s; }

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
    ctx.alarms.raise(axis_bit(axis), Alarm{code, run.phase, AxisField::none, value, 0});
  }
  void move_to(double target_mm, double v) {
    run.target_mm = target_mm;
    if (starts_into_limit(target_mm)) return;
    run.command = move_to_command(run.motor, target_mm, v, accel, dt());
  }
  // A motion from rest toward an active limit switch: raised instead (cam_phases.cpp).
  bool starts_into_limit(double target_mm);
  void wait_for(Wait w, Phase next) {
    enter(Phase::waiting);
    run.phase_data<phase_data::Waiting>() = {w, next, ctx.time_s};
  }

  // -- phases (search_phases, edge_phases, home_phases, pair_phases.cpp) ----
  void pre_move();
  void clear_sensors();  // a gantry on its sensors
  void seek();
  void stop();
  bool stopped_on_sensor();
  void after_stop();
  void push();
  void push_to_stop();  // hard-stop homing (stop_phases.cpp)
  std::optional<AlarmCode> push_cannot_start() const;
  struct Following {
    double error_mm;     // the steps' lead over the encoder, toward the stop
    double followed_mm;  // the encoder's travel toward the stop
  };
  Following following(const phase_data::PushToStop& push) const;
  void back_off();
  void reapproach();
  void latch_edge_found(double edge_mm);
  // The index search runs away from the sensor (-dir) from the release edge.
  bool beyond(double release_mm, double x_mm) const { return (x_mm - release_mm) * -dir > 0; }
  void index();
  void note_index(double release_mm, double index_mm);
  void reference_found(double reference_mm);
  void note_gantry_skew();
  double rest_offset_mm() const;
  void pull_off();
  void aligned();
  void set_home(Run& r, std::size_t of_axis, double reference_motor_mm, double machine_mm_at_rest);
  void set_home(double reference_motor_mm, double machine_mm_at_rest);
  double travel_within_square() const;  // search_phases.cpp
  void fail_off_square();
  void note_square();
  void assign();
  void after_assign();
  void final_move();
  void waiting();
  void align_slave();
  void drive_homing();  // drive_phases.cpp
  // Home cam in mid-travel (cam_phases.cpp).
  void cam_seek();
  void limit_reversal();
  void cam_stop();
  void cam_latch();
  void cam_triggered();
  void fail_limit(AlarmCode code, double toward);
  // The side of the cam its reference edge lies on, as a direction.
  double cam_side() const { return s.cam_edge == CamEdge::ahead ? dir : -dir; }
  // Pull-off: away from the reference edge (from the sensor; a home cam's off the cam on its reference side).
  double away_from_reference() const { return row().runs(Phase::cam_latch) ? cam_side() : -dir; }
  // The reference check (refcheck_phases.cpp): one phase in steps.
  void reference_check();
  void refcheck_begin(phase_data::RefCheck& c);
  void refcheck_step(phase_data::RefCheck& c, phase_data::RefCheck::Step step, double target_mm);
  void refcheck_cross_cam(phase_data::RefCheck& c);
  void refcheck_leave_sensor(phase_data::RefCheck& c);
  void refcheck_approach(phase_data::RefCheck& c);
  void refcheck_back_off(phase_data::RefCheck& c);
  void refcheck_judge(phase_data::RefCheck& c, double edge_mm, bool found);
  void refcheck_go_back(phase_data::RefCheck& c);
  void refcheck_release(phase_data::RefCheck& c);
  // The commissioning measurement (measure_phases.cpp): one phase in steps.
  void homed_at_rest();  // done, or on to measure_travel when the cycle measures this axis
  void measure_travel();
  void measure_begin(phase_data::Measure& m);
  bool measure_end_told(const phase_data::Measure& m) const;
  void measure_travel_on(phase_data::Measure& m);
  void measure_brake(phase_data::Measure& m);
  void measure_record(const phase_data::Measure& m);
  void measure_leave(phase_data::Measure& m);
  void measure_settle(phase_data::Measure& m);
  void begin();
  void dispatch();
};

}  // namespace homing
