#pragma once
// The homing engine: a pure step function. Given the settings, the inputs
// sampled this period and the time since the last period, it advances its
// state and returns motion commands, outputs and status. No clocks, threads,
// sleeps, I/O or allocation in here: the runtime owns all of that.
#include <array>
#include <cstdint>
#include <optional>

#include "alarm_sink.hpp"
#include "axis_run.hpp"
#include "input_channel.hpp"
#include "io.hpp"
#include "settings.hpp"
#include "sequence.hpp"
#include "settings_check.hpp"
#include "status.hpp"

namespace homing {

struct PhaseContext;

struct StepResult {
  const Outputs& outputs;
  const Status& status;
};

class Engine {
 public:
  Engine();
  StepResult step(const Settings& settings, const Inputs& inputs, double dt_s);
  const Outputs& outputs() const { return outputs_; }
  const Status& status() const { return status_; }
  // Nothing that time alone moves on: no cycle or wind-down, every axis
  // idle and at rest with no motion commanded and its indexer settled, no
  // home input's debounce pending. While quiet, a step with any dt and the
  // same inputs changes nothing but the engine's time and heartbeat, so the
  // runtime may run periods far apart until an input or a command changes.
  bool quiet() const;

 private:
  // One period, in this order (engine.cpp).
  void advance_motion(double dt_s);
  void read_inputs(const Settings& settings, const Inputs& inputs, double dt_s);  // sensor_inputs.cpp
  void check_safety(const Settings& settings, const Inputs& inputs);              // safety.cpp
  void check_drive_references(const Settings& settings);
  void check_limit_switches(const Settings& settings);                             // limit_switches.cpp
  void handle_commands(const Settings& settings, const Inputs& inputs);
  void restore_last_stops(const Settings& settings, const LastStops& stops);          // refcheck.cpp
  void run_cycle(const Settings& settings);                                       // cycle.cpp
  void run_motion(const Settings& settings);                                      // jog_move.cpp
  void follow_masters(const Settings& settings);                                  // gantry_guard.cpp
  void guard_gantries(const Settings& settings);
  static GantrySide side_at_fault(const AxisRun& slave, const AxisRun& master);
  void release_commutators(const Settings& settings);
  void run_indexers(const Settings& settings, const Inputs& inputs);              // indexer.cpp
  void keep_home_frames(const Settings& settings);                                // home_frame.cpp
  void publish(const Settings& settings, const Inputs& inputs);                   // publish.cpp
  void route_outputs(const Settings& settings);                                   // output_routing.cpp

  // The alarm path (alarm_path.cpp): the only code that writes an alarm.
  void raise(const Settings& settings, AxisMask axes, Alarm alarm);
  void raise_global(const Settings& settings, AlarmCode code);
  void halt(const Settings& settings);
  void unhome_on_alarm(const Settings& settings, AxisMask spared = 0);
  void stop_all(const Settings& settings);
  void stop_axis(const Settings& settings, std::size_t axis);
  void clear_alarms();
  void reset_command();
  void abort_command(const Settings& settings);
  void cancel_starts(const Inputs& inputs);

  // What a failed cycle does next, by global.failure_policy (failure_policy.cpp).
  enum class WindDown : std::uint8_t {
    none,       // no failed cycle winding down
    finishing,  // finish_independent: the running step's independent axes finish
    returning,  // return_to_start: the axes that moved go back, the last step first
  };
  WindDown wind_down_for(const Settings& settings, AlarmCode code) const;
  void after_alarm(const Settings& settings, AlarmCode code);
  void finish_independent(const Settings& settings);
  void begin_return(const Settings& settings);
  AxisMask returning_axes(const Settings& settings) const;
  bool may_return(const Settings& settings, std::size_t axis) const;
  void run_return(const Settings& settings);
  bool next_return_step();
  bool return_axis(const Settings& settings, std::size_t axis, bool all_at_rest);
  void end_wind_down();

  // Homing (cycle.cpp; the phases of one axis in axis_phases.cpp).
  CommandResult homing_refusal(const Settings& settings) const;
  void home_command(const Settings& settings, const Inputs& inputs);
  void unhome_command(const Settings& settings, AxisMask axes);
  void set_position_commands(const Settings& settings, const Commands& c);
  void start_cycle(const Settings& settings, AxisMask requested, bool all, AxisMask measure = 0);
  bool start_step(const Settings& settings);
  void assign_unsequenced(const Settings& settings, std::size_t axis);
  AxisMask keeps_coordinate(const Settings& settings, AxisMask unsequenced) const;
  void finish_cycle(const Settings& settings);
  void begin_axis(const Settings& settings, std::size_t axis);
  void run_axis(const Settings& settings, std::size_t axis);
  bool steps_run() const { return cycle_active_ && wind_down_ != WindDown::returning; }
  bool cycle_runs(std::size_t axis) const { return steps_run() && axes_[axis].in_cycle; }

  // The reference check (refcheck.cpp; its phase in refcheck_phases.cpp).
  CommandResult refcheck_refusal(const Settings& settings, std::size_t axis) const;
  void refcheck_command(const Settings& settings, AxisMask axes);
  void start_refcheck(AxisMask axes);

  // The commissioning measurement (measure.cpp; its phase in measure_phases.cpp).
  CommandResult measure_refusal(const Settings& settings, std::size_t axis) const;
  void measure_command(const Settings& settings, AxisMask axes);

  // Jog and move (jog_move.cpp).
  CommandResult motion_refusal(const Settings& settings, std::size_t axis) const;
  CommandResult jog_refusal(const Settings& settings, std::size_t axis, std::int8_t dir) const;
  template <typename Pred>
  bool any_of_pair(const Settings& settings, std::size_t axis, Pred pred) const;
  bool on_both_limits(const Settings& settings, std::size_t axis) const;
  bool limit_ahead(const Settings& settings, std::size_t axis, double toward) const;
  bool on_limit_switch(const Settings& settings, std::size_t axis) const;
  void jog_commands(const Settings& settings, const Commands& commands);
  void move_commands(const Settings& settings, const Commands& commands);

  bool any_alarm() const;
  bool any_motion() const;
  // Input channels (sensor_inputs.cpp).
  int sensor_channel(const Settings& settings, std::size_t axis) const;
  int channel_owner(const Settings& settings, std::size_t channel) const;

  bool any_drive_fault() const;
  // The phases of one axis run over this context (phase_runner.hpp).
  class Alarms final : public AlarmSink {
   public:
    Alarms(Engine& engine, const Settings& settings) : engine_(engine), settings_(settings) {}
    void raise(AxisMask axes, Alarm alarm) override { engine_.raise(settings_, axes, alarm); }

   private:
    Engine& engine_;
    const Settings& settings_;
  };
  PhaseContext make_context(const Settings& settings, std::size_t axis, Alarms& alarms);

  std::array<AxisRun, kAxisCount> axes_{};
  std::array<InputChannel, kAxisCount> inputs_{};  // home-sensor inputs, one per axis's channel
  // Each output channel's source: the axis whose motor it drives now, and
  // its position less that motor's (output_routing.cpp).
  struct OutputChannel {
    std::size_t source = 0;
    double offset_mm = 0;
  };
  std::array<OutputChannel, kAxisCount> out_channels_{{{0}, {1}, {2}, {3}, {4}, {5}}};
  double last_dt_s_ = 0.001;
  // The rule set on this period's settings (as configured), computed on first use.
  const SettingsFaults& faults() const;
  const Settings* configured_ = nullptr;  // valid during step() only
  mutable SettingsFaults faults_{};
  mutable bool faults_checked_ = false;

  double time_s_ = 0;
  bool first_step_ = true;
  bool cycle_active_ = false;
  bool cycle_all_ = false;
  bool cycle_is_check_ = false;  // the running cycle is a reference check
  AxisMask cycle_requested_ = 0;
  CyclePlan plan_{};
  int step_index_ = -1;          // index into plan_.steps of the running (or returning) step
  WindDown wind_down_ = WindDown::none;
  std::uint32_t wind_down_period_ = 0;  // the period (heartbeat_) the failed cycle began to wind down
  int first_alarm_axis_ = -1;    // the axis that latched the first alarm since the last reset
  AlarmCode global_alarm_ = AlarmCode::none;
  // Alarms latched in this period: nobody has seen them yet, so a reset in
  // the same period must not clear them (seed 2818140234).
  AxisMask raised_now_ = 0;
  bool global_raised_now_ = false;
  bool estop_ = false;
  bool prev_start_button_ = false;
  bool comm_lost_ = false;
  bool heartbeat_stale_ = false;  // shown as the communication_lost interlock, moving or not
  bool permit_ = false;
  std::uint32_t homing_cycles_ = 0;
  std::uint32_t heartbeat_ = 0;
  CommandResult last_result_ = CommandResult::none;
  std::uint32_t command_count_ = 0;

  Outputs outputs_{};
  Status status_{};
};

}  // namespace homing
