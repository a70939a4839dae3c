// A seeded random campaign: random settings, sensor placements, faults and
// aborts at random moments, and control periods of random length (a shared
// machine's loop can be several milliseconds late). Invariants checked every
// period and at the end of every cycle:
//   - no move past a mechanical stop (the carriage touches one only while pushing);
//   - no move past an enforced soft limit;
//   - no motion while an alarm is latched, once the axis has come to rest, and
//     the stop after an alarm within the deceleration distance;
//   - every cycle ends homed or in an alarm, within its bounded distance;
//   - a homed axis's position matches the simulator's truth;
//   - an alarm appears only when its fault was injected.
//
// Run count: environment variable HOMING_CAMPAIGN_RUNS (default 3000, which
// keeps the whole homing suite well under a minute on a 2-core machine in a
// RelWithDebInfo build; a soak run can ask for millions). The first seed is
// HOMING_CAMPAIGN_SEED (default 1); run i uses seed first + i, so a failure
// names the seed that reproduces it: HOMING_CAMPAIGN_SEED=<seed> HOMING_CAMPAIGN_RUNS=1.
#include <catch2/catch.hpp>

#include <cstdio>
#include <cstdlib>
#include <random>
#include <set>
#include <sstream>

#include "rig.hpp"
#include "truth.hpp"
#include "homing/settings_check.hpp"

using namespace rig;

namespace {

std::uint64_t env_u64(const char* name, std::uint64_t fallback) {
  const char* v = std::getenv(name);
  if (!v || !*v) return fallback;
  return std::strtoull(v, nullptr, 10);
}

enum class Injected {
  none,
  stuck_active,
  stuck_inactive,
  wire_break,
  drive_fault,
  abort,
  estop,
  comm_lost,
  permit_off,
  bad_setting,
  short_cam,
  encoder_invalid,
  lost_steps,  // between two homings: home correction must equal them
  count
};

const char* injected_name(Injected f) {
  static const char* names[] = {"none",     "stuck_active", "stuck_inactive", "wire_break", "drive_fault",
                                "abort",    "estop",        "comm_lost",      "permit_off", "bad_setting",
                                "short_cam", "encoder_invalid", "lost_steps"};
  return names[static_cast<int>(f)];
}

struct Run {
  std::uint64_t seed = 0;
  Rig r;
  std::mt19937_64 rng;
  double u(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
  bool chance(double p) { return u(0, 1) < p; }
  template <class T>
  T pick(std::initializer_list<T> items) {
    const auto i = std::uniform_int_distribution<std::size_t>(0, items.size() - 1)(rng);
    return *(items.begin() + static_cast<std::ptrdiff_t>(i));
  }

  Injected fault = Injected::none;
  double fault_time_s = 0;  // machine time into the cycle for the timed faults
  bool fault_applied = false;
  double dir = -1;          // toward the sensor
  double edge_mm = 0;       // trigger edge of the cam (the end the seek meets)
  double max_dt_s = 0.001;
  double path_bound_mm = 0;
  double time_bound_s = 0;
  double lost_mm = 0;
  std::ostringstream story;

  explicit Run(std::uint64_t s) : seed(s), rng(s) {}

  // Mirror: all positions are generated for a negative-homing axis, then
  // flipped for a positive one.
  double m(double x) const { return dir < 0 ? x : -x; }

  void build() {
    AxisSettings& s = r.settings.axes[0];
    sim::AxisConfig& c = r.machine.axes[0];
    r.machine.seed = seed;
    s = typical_axis();
    s.mode = pick({HomingMode::switch_release, HomingMode::switch_release, HomingMode::switch_reapproach,
                   HomingMode::switch_reapproach, HomingMode::switch_index, HomingMode::pushing_release,
                   HomingMode::pushing_reapproach, HomingMode::manual, HomingMode::absolute,
                   HomingMode::absolute_final, HomingMode::disabled});
    dir = chance(0.5) ? -1 : 1;
    s.direction = dir < 0 ? Direction::negative : Direction::positive;
    s.seek_feedrate_mm_per_min = u(300, 3000);
    s.latch_feedrate_mm_per_min = u(20, std::min(300.0, s.seek_feedrate_mm_per_min / 2));
    s.acceleration_mm_per_s2 = u(100, 2000);
    s.debounce_ms = chance(0.5) ? 0 : u(0, 4);
    const double seek_v = mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min);
    const double latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
    const double needed = seek_stop_distance_mm(s);
    // Contact bounce delays the debounced trigger by up to its own length too.
    const double bounce_ms = s.debounce_ms > 1 && chance(0.5) ? u(0, s.debounce_ms * 0.9) : 0;
    s.max_stop_distance_mm = (needed + seek_v * bounce_ms / 1000) * u(1.0, 3.0) + u(0, 0.1);
    max_dt_s = chance(0.3) ? 0.002 : 0.009;  // the latest a period may come
    const double late_travel = seek_v * max_dt_s;
    const double overshoot = s.max_stop_distance_mm + late_travel + 1e-3;  // past the trigger, worst case

    c = typical_sim_axis();
    c.hysteresis_mm = u(0, 0.2);
    c.noise_mm = chance(0.5) ? 0 : u(0, 0.01);
    c.bounce_ms = bounce_ms;
    const bool nc = chance(0.3);
    s.sensor_nc = c.sensor_nc = nc;
    edge_mm = u(-50, 50);
    const double cam_len = overshoot + c.hysteresis_mm + u(0.5, 30);
    s.max_backoff_mm = overshoot + c.hysteresis_mm + 0.1 + u(0.5, 5);
    s.pull_off_mm = chance(0.2) ? 0 : u(0.1, 3);
    s.home_position_mm = u(-10, 10);
    s.pre_move_mode = pick({PreMove::none, PreMove::if_sensor_active, PreMove::always});
    s.pre_move_distance_mm = u(0.5, 5);
    s.push_distance_mm = u(0.3, 3);
    // Backing off from the stop a pushing axis was pushed against takes up to the push distance more.
    if (mode_is_pushing(s.mode)) s.max_backoff_mm += s.push_distance_mm;
    // Start: usually away from the sensor, sometimes already on it.
    double start_gap = u(0.5, 40);
    if (chance(0.15) && !mode_is_pushing(s.mode)) start_gap = -u(0, std::min(cam_len, s.max_backoff_mm - c.hysteresis_mm - 0.2) * 0.8);
    s.max_seek_travel_mm = std::max(start_gap, 0.0) + s.pre_move_distance_mm + overshoot + u(1, 20);
    // Index pulses.
    s.index_pitch_mm = u(1, 5);
    c.index_pitch_mm = s.mode == HomingMode::switch_index ? s.index_pitch_mm : 0;
    c.index_offset_mm = u(0, 5);
    // Mechanical stops: beyond every bounded travel, except that a pushing
    // axis has its stop within the push distance behind the halt point.
    const double far_out = std::abs(start_gap) + s.max_seek_travel_mm + overshoot + 5;
    // Room for jogs and moves within the soft limits (around the rest point) too.
    double stop_in = std::min(edge_mm - far_out, edge_mm - s.pull_off_mm - 60);
    if (mode_is_pushing(s.mode)) stop_in = edge_mm - overshoot - u(0, s.push_distance_mm * 0.8) - 1e-3;
    const double start = edge_mm + start_gap;
    const double stop_out = start + s.pre_move_distance_mm + s.max_backoff_mm + 50;
    // Final move and soft limits (in machine coordinates, around the home position).
    s.final_move_enable = chance(0.3);
    // A pushing axis's stop is just behind its sensor: its final position lies away from it.
    s.final_position_mm = s.home_position_mm + (mode_is_pushing(s.mode) ? -dir * u(0, 20) : u(-20, 20));
    // Absolute modes assign whatever the encoder says: it may lie outside any limits.
    // So may a disabled axis (its coordinates are whatever they were).
    s.soft_limits_enable = chance(0.5) && !mode_is_absolute(s.mode) && s.mode != HomingMode::disabled;
    s.soft_limit_min_mm = std::min(s.home_position_mm, s.final_position_mm) - u(0.5, 30);
    s.soft_limit_max_mm = std::max(s.home_position_mm, s.final_position_mm) + u(0.5, 30);
    s.jog_feedrate_mm_per_min = u(120, 1200);
    // Final move room: the machine coordinate range maps to carriage positions near the rest point.
    const double room = 60 + s.pull_off_mm;
    // The encoder reads near the home position at the start, so a final move stays nearby.
    c.absolute_offset_mm = 2 * s.home_position_mm - m(edge_mm + start_gap) + u(-5, 5);

    // Mirror into the real direction.
    const double cam_a = m(edge_mm), cam_b = m(edge_mm - cam_len);
    c.sensor_min_mm = std::min(cam_a, cam_b);
    c.sensor_max_mm = std::max(cam_a, cam_b);
    c.actual_position_mm = m(start);
    c.hard_stop_min_mm = std::min(m(stop_in), m(stop_out + room));
    c.hard_stop_max_mm = std::max(m(stop_in), m(stop_out + room));
    if (dir > 0) c.index_offset_mm = -c.index_offset_mm;

    // Late periods: most about 1 ms, one in ten late by up to max_dt.
    r.next_dt = [this] {
      return chance(0.1) ? u(0.001, max_dt_s) : u(0.0005, 0.0015);
    };

    // Bounds of the cycle: distance and machine time.
    const double index_bound = s.index_pitch_mm * 1.1 + stop_distance_mm(latch_v, s.acceleration_mm_per_s2);
    const double final_d = s.final_move_enable || s.mode == HomingMode::absolute_final ? 300 : 0;
    path_bound_mm = s.pre_move_distance_mm + s.max_seek_travel_mm + overshoot + s.push_distance_mm +
                    2 * s.max_backoff_mm + index_bound + s.pull_off_mm + s.max_backoff_mm + final_d + 1;
    time_bound_s = 2 * path_bound_mm / latch_v + 10;

    // Fault.
    fault = chance(0.55) ? Injected::none
                         : static_cast<Injected>(std::uniform_int_distribution<int>(1, static_cast<int>(Injected::count) - 1)(rng));
    if (fault == Injected::short_cam && (!mode_uses_switch(s.mode) || mode_is_pushing(s.mode) || start_gap < 0))
      fault = Injected::none;
    if (fault == Injected::encoder_invalid && !mode_is_absolute(s.mode)) fault = Injected::none;
    // Pushing modes lose steps on purpose against the stop: their correction holds those too.
    if (fault == Injected::lost_steps && (!mode_uses_switch(s.mode) || mode_is_pushing(s.mode))) fault = Injected::none;
    fault_time_s = u(0, 3);
    switch (fault) {
      case Injected::stuck_active: c.fault = sim::Fault::sensor_stuck_active; break;
      case Injected::stuck_inactive: c.fault = sim::Fault::sensor_stuck_inactive; break;
      case Injected::wire_break: c.fault = sim::Fault::wire_break; break;
      case Injected::short_cam: {
        // A cam shorter than the stop: the sensor releases while stopping.
        const double stop = stop_distance_mm(seek_v, s.acceleration_mm_per_s2);
        c.hysteresis_mm = std::min(c.hysteresis_mm, 0.3 * stop);
        c.noise_mm = 0;
        const double short_len = (stop - c.hysteresis_mm) * u(0.1, 0.6);
        const double a = m(edge_mm), b = m(edge_mm - short_len);
        c.sensor_min_mm = std::min(a, b);
        c.sensor_max_mm = std::max(a, b);
        break;
      }
      case Injected::bad_setting: {
        const int which = std::uniform_int_distribution<int>(0, 2)(rng);
        // Only settings the mode uses: others are not checked.
        if (!mode_uses_switch(s.mode) && !(s.mode == HomingMode::absolute_final && which == 2)) {
          fault = Injected::none;
          break;
        }
        if (which == 0) s.max_stop_distance_mm = needed * 0.5;
        if (which == 1) s.latch_feedrate_mm_per_min = s.seek_feedrate_mm_per_min;
        if (which == 2) s.acceleration_mm_per_s2 = 0;
        break;
      }
      case Injected::permit_off:
        r.settings.global.permit_required = true;
        break;
      default: break;
    }
    if (fault != Injected::permit_off && chance(0.2)) r.settings.global.permit_required = true;
    r.settings.global.alarm_clears_homed = chance(0.7);
    r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
    // Lost steps: away from the sensor, or toward it by less than the pull-off
    // (deeper would need a longer back-off than this axis has).
    lost_mm = chance(0.5) ? -dir * u(0, 3) : dir * u(0, s.pull_off_mm);
    if (fault == Injected::lost_steps) {
      c.noise_mm = 0;               // else the correction also holds the edge noise
      s.final_move_enable = false;  // the second cycle starts from the rest point
    }

    story << "seed " << seed << " mode " << mode_name(s.mode) << " dir " << dir << " fault " << injected_name(fault)
          << " at " << fault_time_s << " s; start " << c.actual_position_mm << " cam [" << c.sensor_min_mm << ", "
          << c.sensor_max_mm << "] stops [" << c.hard_stop_min_mm << ", " << c.hard_stop_max_mm << "] seek "
          << s.seek_feedrate_mm_per_min << " latch " << s.latch_feedrate_mm_per_min << " accel "
          << s.acceleration_mm_per_s2 << " debounce " << s.debounce_ms << " bounce " << c.bounce_ms << " max_stop "
          << s.max_stop_distance_mm << " max_backoff " << s.max_backoff_mm << " pre_move "
          << static_cast<int>(s.pre_move_mode) << " nc " << nc << " max_dt " << max_dt_s;
  }

  std::set<AlarmCode> allowed() const {
    const AxisSettings& s = r.settings.axes[0];
    const bool sw = mode_uses_switch(s.mode);
    switch (fault) {
      case Injected::none: return {};
      case Injected::stuck_active: return sw ? std::set{AlarmCode::not_released} : std::set<AlarmCode>{};
      case Injected::stuck_inactive: return sw ? std::set{AlarmCode::sensor_not_found} : std::set<AlarmCode>{};
      case Injected::wire_break:
        return sw ? std::set{s.sensor_nc ? AlarmCode::not_released : AlarmCode::sensor_not_found} : std::set<AlarmCode>{};
      case Injected::drive_fault: return {AlarmCode::drive_fault};
      case Injected::abort: return {AlarmCode::aborted};
      case Injected::estop: return {AlarmCode::emergency_stop};
      case Injected::comm_lost: return {AlarmCode::communication_lost};
      case Injected::permit_off: return {AlarmCode::permit_withdrawn};
      case Injected::bad_setting: return {AlarmCode::settings_fault};
      // A cam passed in less than the debounce time is never seen at all.
      case Injected::short_cam: return {AlarmCode::overrun_during_stop, AlarmCode::sensor_not_found};
      case Injected::encoder_invalid: return {AlarmCode::encoder_fault};
      case Injected::lost_steps: return {};
      case Injected::count: break;
    }
    return {};
  }
  // Faults that must raise their alarm (the others may come too late to matter).
  bool must_alarm() const {
    if (fault == Injected::bad_setting || fault == Injected::short_cam || fault == Injected::encoder_invalid) return true;
    if (fault == Injected::stuck_active || fault == Injected::stuck_inactive || fault == Injected::wire_break)
      return mode_uses_switch(r.settings.axes[0].mode);
    return false;
  }

  // Timed faults, applied while the cycle runs.
  bool comm_lost = false;
  void apply_timed(double t_in_cycle) {
    if (fault_applied || t_in_cycle < fault_time_s || !r.status().homing) return;
    fault_applied = true;
    switch (fault) {
      case Injected::drive_fault: {
        auto c = r.sim().axis_config(0);
        c.fault = sim::Fault::drive_fault;
        r.sim().set_axis_config(0, c);
        break;
      }
      case Injected::abort: r.pending.abort = true; break;
      case Injected::estop: r.sim().set_estop(true); break;
      case Injected::comm_lost: comm_lost = true; break;
      case Injected::permit_off: r.sim().set_homing_permit(false); break;
      default: fault_applied = false; break;
    }
  }

  // --- per-period invariants ----------------------------------------------
  bool alarm_seen = false;
  bool rested_in_alarm = false;
  double alarm_rest_mm = 0;
  double v_before_mm_per_s = 0, x_before_alarm_mm = 0;
  double prev_v = 0, prev_x = 0;
  std::string failure;

  void fail(const std::string& what) {
    if (failure.empty()) failure = what;
  }

  Phase traced_phase = Phase::idle;
  bool trace_on = std::getenv("HOMING_CAMPAIGN_TRACE") != nullptr;  // phase changes on stdout

  void check_period() {
    const AxisSettings& s = r.settings.axes[0];
    if (trace_on && r.axis(0).phase != traced_phase) {
      traced_phase = r.axis(0).phase;
      std::printf("t %.4f phase %s carriage %.5f position %.5f v %.3f alarm %s homed %d\n", r.sim().time_s(),
                  std::string(phase_name(traced_phase)).c_str(), r.actual(0), r.axis(0).position_mm,
                  r.axis(0).velocity_mm_per_s, std::string(alarm_name(r.axis(0).alarm.code)).c_str(),
                  r.axis(0).homed);
    }
    const double x = r.actual(0);
    const AxisStatus& st = r.axis(0);
    if (r.sim().at_hard_stop(0) && !mode_is_pushing(s.mode))
      fail(std::string("carriage at a mechanical stop in phase ") + std::string(phase_name(st.phase)));
    // A pushing axis's stop lies just behind its sensor: a dead sensor lets the seek run into it.
    const bool dead_sensor = fault == Injected::stuck_inactive || (fault == Injected::wire_break && !s.sensor_nc);
    if (r.sim().at_hard_stop(0) && mode_is_pushing(s.mode) && st.phase != Phase::push && !r.status().alarm &&
        st.phase != Phase::back_off && !(dead_sensor && st.phase == Phase::seek))
      fail(std::string("carriage held at the stop outside the push phase: ") + std::string(phase_name(st.phase)));
    if (st.homed && !r.status().homing && s.soft_limits_enable && s.mode != HomingMode::disabled && !r.status().alarm &&
        (st.position_mm < s.soft_limit_min_mm - 1e-6 || st.position_mm > s.soft_limit_max_mm + 1e-6))
      fail("position beyond an enforced soft limit");
    if (r.status().alarm) {
      if (!alarm_seen) {
        alarm_seen = true;
        // The motor's speed when the alarm was raised (the status shows it at the step).
        v_before_mm_per_s = std::max(std::abs(prev_v), std::abs(st.velocity_mm_per_s));
        x_before_alarm_mm = prev_x;
      }
      const double decel = stop_distance_mm(std::abs(v_before_mm_per_s), s.acceleration_mm_per_s2) +
                           std::abs(v_before_mm_per_s) * max_dt_s + 1e-6;
      if (std::abs(x - x_before_alarm_mm) > decel) fail("travelled beyond the deceleration distance after an alarm");
      if (rested_in_alarm && x != alarm_rest_mm) fail("motion while an alarm is latched");
      if (!rested_in_alarm && st.velocity_mm_per_s == 0 && !r.sim().moving(0)) {
        rested_in_alarm = true;
        alarm_rest_mm = x;
      }
    }
    prev_v = st.velocity_mm_per_s;
    prev_x = x;
    // The reference edges, as they stand while the edge search runs (a later
    // final move may cross the sensor again).
    if (st.phase == Phase::seek || st.phase == Phase::stop || st.phase == Phase::push ||
        st.phase == Phase::back_off || st.phase == Phase::reapproach || st.phase == Phase::index) {
      if (auto e = r.sim().last_edge(0, false)) release_mm = e->actual_mm;
      if (auto e = r.sim().last_edge(0, true)) trigger_mm = e->actual_mm;
    }
  }
  double release_mm = NAN, trigger_mm = NAN;

  // Rest point implied by the simulator's edges for the mode used.
  double expected_rest() {
    const AxisSettings& s = r.settings.axes[0];
    if (mode_reapproaches(s.mode)) return rest_point_mm(s, trigger_mm);
    const double release = release_mm;
    if (s.mode == HomingMode::switch_index) {
      const auto& c = r.sim().axis_config(0);
      // First pulse beyond the release edge in the back-off direction (-dir).
      const double k = dir < 0 ? std::floor((release - c.index_offset_mm) / c.index_pitch_mm) + 1
                               : std::ceil((release - c.index_offset_mm) / c.index_pitch_mm) - 1;
      return rest_point_mm(s, c.index_offset_mm + k * c.index_pitch_mm);
    }
    return rest_point_mm(s, release);
  }

  // One cycle: returns false when it failed to end.
  bool cycle() {
    r.clear_trace();
    r.pending.home_all = true;
    const double t0 = r.sim().time_s();
    r.step();
    while (r.status().homing && r.sim().time_s() - t0 < time_bound_s) {
      apply_timed(r.sim().time_s() - t0);
      r.step();
    }
    if (r.status().homing) {
      fail("cycle did not end within its time bound");
      return false;
    }
    r.run_until([&] { return !r.any_moving(); }, 5);
    if (r.trace[0].path_mm > path_bound_mm) fail("cycle travelled beyond its bounded distance");
    return true;
  }

  void check_end() {
    const AxisSettings& s = r.settings.axes[0];
    const AlarmCode code = r.axis(0).alarm.code;
    const AlarmCode global = r.status().global_alarm;
    const auto ok = allowed();
    if (code != AlarmCode::none && !ok.count(code))
      fail(std::string("alarm ") + std::string(alarm_name(code)) + " without its fault: " +
           describe_alarm(0, r.axis(0).alarm, r.settings));
    if (global != AlarmCode::none && !ok.count(global))
      fail(std::string("global alarm ") + std::string(alarm_name(global)) + " without its fault");
    if (r.status().alarm) {
      if (must_alarm() == false && fault == Injected::none) fail("alarm without a fault");
      if (code == AlarmCode::settings_fault && r.trace[0].path_mm != 0) fail("moved before a settings fault");
      return;
    }
    if (must_alarm()) fail("an injected fault raised no alarm");
    if (r.status().state != MachineState::homed) {
      fail("cycle ended neither homed nor in alarm");
      return;
    }
    // Homed: the position matches the simulator's truth.
    const double tol = edge_tolerance_mm(s, 0.001) + 1e-9;
    const double x = r.actual(0);
    const double p = r.axis(0).position_mm;
    if (mode_uses_switch(s.mode) && fault != Injected::stuck_active && fault != Injected::stuck_inactive &&
        fault != Injected::wire_break) {
      const double rest = expected_rest();
      const double truth = s.home_position_mm + (x - rest);
      if (std::abs(p - truth) > tol) {
        std::ostringstream o;
        o << "release " << release_mm << " index pitch " << r.sim().axis_config(0).index_pitch_mm << " offset "
          << r.sim().axis_config(0).index_offset_mm << "; homed position " << p << " but the truth is " << truth << " (carriage " << x << ", rest " << rest << ")";
        fail(o.str());
      }
      const bool final_move = s.final_move_enable;
      if (!final_move && std::abs(x - rest) > tol) fail("did not come to rest at pull-off from the edge");
    }
    if (s.mode == HomingMode::absolute || s.mode == HomingMode::absolute_final) {
      const double truth = x + r.sim().axis_config(0).absolute_offset_mm - s.home_position_mm;
      if (std::abs(p - truth) > 1e-9) fail("absolute position differs from the encoder's");
    }
    const bool final_move = s.mode == HomingMode::absolute_final ||
                            (s.final_move_enable && s.mode != HomingMode::absolute && s.mode != HomingMode::disabled);
    if (final_move && std::abs(p - s.final_position_mm) > 1e-9) fail("final move did not end at the final position");
  }

  // After homing: jogs and moves never leave the enforced soft limits.
  void exercise_motion() {
    const AxisSettings& s = r.settings.axes[0];
    r.jog(0, chance(0.5) ? 1 : -1);
    r.run_for(u(0.05, 1.5));
    r.release_jogs();
    r.run_until([&] { return !r.any_moving() && r.axis(0).phase != Phase::stopping; }, 10);
    const double target = r.axis(0).position_mm + u(-40, 40);
    r.move(0, target);
    const bool outside = s.soft_limits_enable && (target < s.soft_limit_min_mm || target > s.soft_limit_max_mm);
    const CommandResult res = r.status().last_command_result;
    if (outside && res != CommandResult::refused_soft_limit) fail("move outside the soft limits not refused");
    if (!outside && res != CommandResult::accepted)
      fail(std::string("move inside the soft limits refused: ") + std::string(command_result_name(res)) + " " +
           describe_alarm(0, r.axis(0).alarm, r.settings));
    r.run_until([&] { return !r.any_moving() && r.axis(0).phase == Phase::idle; }, 60);
    if (!outside && std::abs(r.axis(0).position_mm - target) > 1e-9) fail("move did not arrive");
  }

  void run() {
    build();
    r.on_period = [this](Rig&) { check_period(); };
    r.tweak_inputs = [this](Inputs& in) {
      in.communication_lost = comm_lost;
      if (fault == Injected::encoder_invalid) in.axes[0].absolute_valid = false;
    };
    r.sim().set_homing_permit(true);
    r.step();
    if (!cycle()) return;
    check_end();
    if (!failure.empty()) return;
    if (fault == Injected::lost_steps && r.status().state == MachineState::homed) {
      r.sim().lose_steps(0, lost_mm);
      if (r.sim().at_hard_stop(0)) return;
      // Lost steps toward the sensor may put the carriage on it: that is fine.
      if (!cycle()) return;
      check_end();
      const double tol = edge_tolerance_mm(r.settings.axes[0], 0.001) + 1e-9;
      if (r.status().state == MachineState::homed && std::abs(r.axis(0).home_correction_mm - lost_mm) > tol)
        fail("home correction " + std::to_string(r.axis(0).home_correction_mm) + " differs from the lost steps " +
             std::to_string(lost_mm));
    }
    // Jogs and moves after homing, where the soft limits keep them off the stops.
    const AxisSettings& s = r.settings.axes[0];
    if (!r.status().alarm && s.soft_limits_enable && !mode_is_pushing(s.mode) && chance(0.5)) exercise_motion();
  }
};

}  // namespace

TEST_CASE("seeded random campaign: settings, placements, faults, aborts and late periods", "[campaign]") {
  const std::uint64_t runs = env_u64("HOMING_CAMPAIGN_RUNS", 3000);
  const std::uint64_t first = env_u64("HOMING_CAMPAIGN_SEED", 1);
  std::uint64_t failures = 0, homed = 0, alarmed = 0;
  for (std::uint64_t i = 0; i < runs; ++i) {
    Run run(first + i);
    run.run();
    if (run.r.status().alarm) ++alarmed; else ++homed;
    if (!run.failure.empty()) {
      ++failures;
      if (failures <= 10) {
        INFO(run.story.str());
        FAIL_CHECK(run.failure);
      }
    }
  }
  INFO(runs << " runs: " << homed << " without alarm, " << alarmed << " in alarm");
  CHECK(failures == 0);
  CHECK(homed > 0);
}
