#pragma once
// The invariants checked every control period against the simulator's truth,
// and the truth itself: where each homed axis's machine coordinate must be.
#include <array>
#include <optional>
#include <cmath>
#include <cstdint>
#include <string>

#include "../rig.hpp"
#include "machine.hpp"

namespace campaign {

// A set of alarm codes, one bit per AlarmCode.
using AlarmBits = std::uint64_t;
static_assert(kAlarmCodeCount <= 64, "AlarmBits holds one bit per alarm code");
constexpr AlarmBits alarm_bit(AlarmCode code) { return AlarmBits{1} << static_cast<unsigned>(code); }

// What the racking check allows beyond max_misalignment besides the travel
// of periods later than the guard looks ahead (docs/homing-methods.md "Gantries: racking"):
// the simulation's floating-point arithmetic.
inline constexpr double kRackingTolerance_mm = 1e-3;
// What the limit-switch check allows past a switch besides the stop from the
// speed the carriage had when it tripped and one late period of travel.
inline constexpr double kLimitTolerance_mm = 1e-3;

struct Failure {
  std::string what;    // short and stable: the failure's class
  std::string detail;  // figures of this instance
};

// machine coordinate = carriage + offset, while valid.
struct Truth {
  bool valid = false;
  double offset = 0;
  double tol = 1e-9;
  bool has_rest = false;  // switch modes: where the axis must rest after pull-off
  double rest = 0;
};

class Watch {
 public:
  Watch(rig::Rig& r, const Machine& m);

  void period();  // every control period, after the simulator ran it

  // The script tells what may move.
  void begin_window(const CyclePlan& plan, bool refused);
  void end_window();                     // the machine is at rest after the cycle
  void set_outside_movers(AxisMask mask);  // jogs and moves between cycles
  // A gantry slave's pair: how far out of square its carriages stand now,
  // counted from where they stood when the pair was last assigned its home
  // (or where the first cycle found it), as the module counts; nullopt once a
  // side lost steps or slipped since (the module's square is then not the
  // carriages'), 0 when nothing is known yet.
  std::optional<double> pair_rack(std::size_t slave) const;
  void pair_unhomed(AxisMask axes);  // the module was told to forget these pairs' square
  double rack_at_window_start(std::size_t slave) const { return rack0_[slave]; }
  void carriage_jumped(std::size_t a);   // lost steps: coordinates no longer known
  void assign_unsequenced();             // a home-all ended: unsequenced axes now hold their home position
  void carriages_placed();               // put back by hand: gantries locked where they stand now
  void pair_slipped(std::size_t a);
  // A new engine (the daemon restarted): it takes each pair as square where
  // it stands, as at power-up; a pair not homed before may stand racked (an
  // alarm left it so), which the module can no longer see (homed: bit per axis).
  void restarted(AxisMask homed);
  void settings_changed();               // written between cycles: what each axis moves with now      // a drive fault on a locked side: the pair may rack up to its limit

  void fail(const std::string& what, const std::string& detail = "");
  bool failed() const { return !failure_.what.empty(); }
  const Failure& failure() const { return failure_; }

  std::array<Truth, kAxisCount> truth{};
  AxisMask dead_sensor = 0;     // a sensor that can no longer trigger (pushing seeks may hit the stop)
  AxisMask tampered = 0;        // a sensor fault during this window: its edges are not the cam's
  AxisMask stuck_on = 0;        // a sensor forced active (stuck active, an open NC circuit)
  AxisMask lock_struck = 0;     // an indexer's pin went in under an axis unlocked for motion (until recovered)
  AlarmBits alarms_seen = 0;  // bit per AlarmCode, any axis or global, since clear_alarms_seen()
  std::array<AlarmBits, kAxisCount> axis_alarms{};  // ... per axis
  AlarmBits global_alarms = 0;                      // ... as the global alarm
  std::array<Alarm, kAxisCount> first_alarm{};          // the first each axis latched, with its phase
  void clear_alarms_seen();
  AxisMask flipped = 0;         // axes the engine marked homed during the window
  std::array<double, kAxisCount> path{};  // carriage path in the window
  bool in_window = false;
  double window_start_s = 0;
  std::array<double, kAxisCount> window_start_x{};
  CyclePlan plan{};
  bool refused = false;
  // A measurement in this window (cmd.measure): its axis ends at the far end
  // of its travel, not at its rest point, and travels that much further.
  AxisMask measured = 0;
  // Left beyond its soft limits by a measurement: not held to them until it
  // is back inside or homed again.
  AxisMask outside_soft_limits = 0;
  std::array<double, kAxisCount> extra_path{};
  std::uint64_t trace_axes = 0;  // HOMING_CAMPAIGN_TRACE: phase changes on stdout
  // home_cam: the axes whose search reversed at a limit switch in this window,
  // those whose cam lay behind the carriage (or beyond the switch ahead) as
  // it began, and those for which that was known (no fault at the start).
  AxisMask reversed = 0;
  AxisMask reversal_expected = 0;
  AxisMask reversal_known = 0;
  bool powering_up = false;      // no command may be judged yet (a start button held since power-up)
  bool powerup_started = false;  // ... and yet one was: what it moved is that failure, not another

  double accel_limit(std::size_t a) const;

  // The failure policy at work since the first alarm of the window
  // (policy_watch.cpp): what each axis may do while the alarm is latched.
  enum class After : std::uint8_t {
    brake,    // stop within its stop distance and stay (stop_all, every axis after a machine-wide cause)
    finish,   // finish_independent: go on homing (an axis of the running step not linked to a failed one)
    go_back,  // return_to_start: brake, then back to where the window found it
  };
  std::array<After, kAxisCount> after{};
  FailurePolicy wind_down = FailurePolicy::stop_all;  // what the window's first alarm started
  AxisMask finishers = 0;      // finish_independent: still homing at the first alarm, going on
  AxisMask returners = 0;      // return_to_start: the axes the rule sends back
  bool later_failure = false;  // another alarm, or an abort, came after the first
  void abort_applied() { abort_pending_ = true; }  // the script aborted: read in the next period
  // Any other fault or command the script applied: while a failure policy is
  // at work it may stop what goes on without a new alarm to show for it (a
  // drive fault on an axis already aborted, a lost link): from then on the
  // policy's end is not required (later_failure).
  void event_applied() { event_pending_ = true; }
  // Where an axis sent back may end: within this of where the window found it.
  double back_tolerance(std::size_t a) const;
  // Its carriage met a mechanical stop in this window: its motor may have
  // run on without it (lost steps the engine cannot see).
  bool stop_touched(std::size_t a) const { return stop_touched_[a]; }

 private:
  void axis_period(std::size_t a, double engine_dt);
  void racking(double engine_dt);
  void on_flip(std::size_t a, double x);
  bool reference_edge(std::size_t a, double& ref);
  void track_edges(std::size_t a);
  void limit_overrun(std::size_t a, double x, double speed);
  // The failure policy (policy_watch.cpp).
  void policy_period(const Status& st);
  void first_failure(const Status& st, AxisMask alarmed);
  void later_failure_at(const Status& st, AxisMask stopped);
  AxisMask go_back_rule(const Status& st) const;
  void brake_from_now(std::size_t a, const Status& st);
  void after_alarm(std::size_t a, double x, double v, bool moved);
  void braking(std::size_t a, double x, double v);
  void going_back(std::size_t a, double x, double v, bool moved);
  bool back_at_start(std::size_t a, double x) const;
  void cam_reversal(std::size_t a);

  rig::Rig& r_;
  const Machine& m_;
  std::array<AxisSettings, kAxisCount> eff_{};  // what each axis homes with (the settings never change in a run)
  Failure failure_{};
  std::array<double, kAxisCount> x_prev_{}, v_prev_{};
  std::array<bool, kAxisCount> homed_prev_{};
  std::array<bool, kAxisCount> grace_{};        // braking after its motion was taken away
  std::array<bool, kAxisCount> pushed_to_stop_{};
  AxisMask outside_ = 0;
  double ran_dt_prev_ = 0.001;
  // Alarm braking.
  bool alarm_prev_ = false;
  int alarm_periods_ = 0;
  std::array<double, kAxisCount> alarm_v0_{}, alarm_x0_{};
  std::array<bool, kAxisCount> rested_{};
  std::array<double, kAxisCount> rest_x_{};
  std::array<int, kAxisCount> brake_periods_{};
  // The failure policy.
  bool homing_prev_ = false;
  int step_prev_ = 0;
  std::uint32_t cycles_prev_ = 0;  // status.homing_cycles at the end of the last period
  AxisMask alarmed_prev_ = 0;
  AlarmCode global_prev_ = AlarmCode::none;
  std::array<AlarmCode, kAxisCount> code_prev_{};
  AxisMask first_axes_ = 0;      // the axes that latched in the first period any axis did
  bool abort_pending_ = false;
  bool event_pending_ = false;
  std::array<bool, kAxisCount> started_on_limit_{};  // a limit switch active as the window began
  std::array<bool, kAxisCount> steps_off_{};  // seen pushing into its stop or homed by its drive in this window
  std::array<bool, kAxisCount> back_{};       // go_back: at rest where the window found it
  std::array<bool, kAxisCount> stop_touched_{};
  // The limit switches read dead in this window (fault limits_dead), though
  // a fault injected later may have taken that fault's place in the simulator.
  std::array<bool, kAxisCount> limits_dead_seen_{};
  std::array<bool, kAxisCount> pre_move_met_stop_{};  // a pre-move started nearer the far stop than its length met it
  std::array<bool, kAxisCount> started_at_stop_{};  // the window found the carriage at its mechanical stop
  std::array<bool, kAxisCount> went_back_{};  // go_back: moved after it had come to rest
  // Gantry racking.
  std::array<double, kAxisCount> rel_ref_{};   // per slave
  // Per slave: the carriages' slave - master when the pair was last square;
  // a side lost steps or slipped since; how far from square the window found
  // them; the pair seen unhomed in this window (its next assignment squares it).
  std::array<std::optional<double>, kAxisCount> square_{};
  std::array<bool, kAxisCount> square_uncertain_{};
  std::array<double, kAxisCount> rack0_{};
  std::array<bool, kAxisCount> rack0_uncertain_{};
  std::array<bool, kAxisCount> pair_unhomed_seen_{};
  // In this window: a side of the pair seen on its way (not done, not idle),
  // so that both done afterwards is this cycle's assignment.
  std::array<bool, kAxisCount> pair_under_way_{};
  double carriage_rel(std::size_t slave) const;
  void square_unsure(std::size_t axis);
  std::array<double, kAxisCount> late_allowance_{};
  std::array<bool, kAxisCount> slipped_{};      // per slave: a side's drive faulted outside a cycle  // per slave: travel in periods later than the guard looks
  // Sensor edges as they stood before this period (the reference of an axis assigned now).
  std::array<double, kAxisCount> release_{}, trigger_{};
  std::array<bool, kAxisCount> has_release_{}, has_trigger_{};
  std::array<Phase, kAxisCount> traced_{};
  std::array<Phase, kAxisCount> phase_prev_{};
  std::array<Phase, kAxisCount> pair_phase_prev_{};  // each gantry side's phase before this period (racking)
  // Limit switches: past one since the period it tripped, at that speed.
  std::array<bool, kAxisCount> past_limit_{};
  std::array<double, kAxisCount> trip_speed_{};
  std::array<bool, kAxisCount> trip_fresh_{};  // tripped in the last period: its end speed comes now
  // The limit switches as the engine reads them in the next period (the
  // simulator's levels at the end of this one).
  std::array<bool, kAxisCount> limit_min_read_{}, limit_max_read_{};
  // The switch ahead read in some period while a locking indexer held the
  // axis (status shows unlock; the phase under it runs and decides).
  std::array<bool, kAxisCount> ahead_while_held_{};
};

// Where an axis homed on reference edge `ref` (carriage coordinates) rests:
// pull-off away from it (a slave's compensation too), for a home cam off the
// cam on its cam_edge side (docs/limit-switches.md).
double rest_from_edge(const AxisSettings& e, double ref, double compensation_mm);

// A home cam axis off its cam, the cam not between the carriage and the limit
// switch ahead (behind it, or beyond that switch): its search must reverse.
bool cam_lies_behind(rig::Rig& r, const AxisSettings& e, std::size_t a);

}  // namespace campaign
