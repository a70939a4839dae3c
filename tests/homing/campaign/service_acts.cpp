// The service acts of a run (issue 23): the commissioning measurement
// (cmd.measure; docs/homing-methods.md "Commissioning measurement") and a
// restart of the daemon followed by reference checks (cmd.refcheck;
// "Position trust and the reference check"). Both are judged from the
// simulator's truth: the travel from where the simulated machine has its
// limit switch or hard stop, a checked axis's coordinate from where its
// carriage really stands. From their own dice (streams 18 and 19): what the
// other acts draw stays as it was.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "../truth.hpp"
#include "homing/last_stop.hpp"
#include "homing/motion.hpp"
#include "run.hpp"

namespace campaign {

namespace {

// The longest a measurement's travel at latch feedrate may take for the act
// to draw it (machine time): a few thousand periods, so that a run stays
// about as long as it was (the generator pulls some far ends in for it).
constexpr double kMeasureBudget_s = 30;

std::string fig(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

// Methods whose home lies at an end of the travel (docs: a measurement of
// manual, absolute, absolute_final, drive and home_cam is refused).
bool homes_at_an_end(HomingMode m) {
  return m == HomingMode::switch_release || m == HomingMode::switch_reapproach || m == HomingMode::switch_index ||
         m == HomingMode::pushing_release || m == HomingMode::pushing_reapproach || m == HomingMode::hard_stop;
}

// Methods the docs offer a reference check: those homing on a switch edge alone.
bool offers_check(HomingMode m) {
  return m == HomingMode::switch_release || m == HomingMode::switch_reapproach || m == HomingMode::home_cam;
}

// The far end of the travel a measurement of this axis looks for, in
// carriage coordinates: its limit switch, or its hard stop (nullopt: none).
std::optional<double> far_end(const AxisSettings& s, const sim::AxisConfig& c) {
  const double toward = -dir_of(s);
  if (s.limits_fitted) return toward > 0 ? c.limit_max_mm : c.limit_min_mm;
  if (s.mode == HomingMode::hard_stop && s.stall_detect == StallDetect::stall_input)
    return toward > 0 ? c.hard_stop_max_mm : c.hard_stop_min_mm;
  return std::nullopt;
}

}  // namespace

// --- the commissioning measurement ------------------------------------------

// The docs' refusals, machine-wide first (more than one axis, single-axis
// homing off), then the axis's own.
CommandResult Run::measure_expected(AxisMask mask) {
  int n = 0;
  std::size_t a = 0;
  for (std::size_t i = 0; i < kAxisCount; ++i)
    if (mask & axis_bit(i)) {
      ++n;
      a = i;
    }
  if (n != 1) return CommandResult::refused_invalid;
  if (!r_.settings.global.single_axis_homing) return CommandResult::refused_home_all_only;
  const AxisSettings& s = r_.settings.axes[a];
  if (s.mode == HomingMode::disabled) return CommandResult::refused_invalid;
  if (partner_index(r_.settings, a) >= 0) return CommandResult::refused_gantry_pair;
  if (!homes_at_an_end(s.mode) || !far_end(s, r_.sim().axis_config(a))) return CommandResult::refused_no_travel_end;
  return CommandResult::accepted;
}

// How far past the far end the measurement may read it: a limit switch is
// read one period after the carriage reached it (a late period at most
// max_dt); against a hard stop the motor runs on at latch feedrate until the
// stall output comes (its detection time and spread) and is read, then brakes.
double Run::measure_lag_mm(std::size_t a) {
  const AxisSettings& s = r_.settings.axes[a];
  const sim::AxisConfig& c = r_.sim().axis_config(a);
  const double latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
  if (s.limits_fitted) return latch_v * m_.max_dt_s + 1e-6;
  return latch_v * ((c.stall_detect_ms + c.stall_spread_ms) / 1000 + 2 * m_.max_dt_s) +
         stop_distance_mm(latch_v, s.acceleration_mm_per_s2) + 1e-6;
}

void Run::measurement() {
  if (!measure_acts_.chance(0.4)) return;
  if (r_.status().alarm || r_.status().homing || r_.any_moving() || comm_lost_ || r_.sim().inputs().estop) return;
  if (r_.settings.global.permit_required && !r_.sim().inputs().homing_permit) return;
  std::vector<std::size_t> refused, measurable;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (on_limit_switch(a)) continue;  // refused_hard_limit: the limit acts judge that
    if (measure_expected(axis_bit(a)) != CommandResult::accepted) {
      refused.push_back(a);
      continue;
    }
    const AxisSettings& s = r_.settings.axes[a];
    const sim::AxisConfig& c = r_.sim().axis_config(a);
    // A machine in order: faults and the causes they bring are the cycles' to judge.
    if (c.fault != sim::Fault::none || ((w_->dead_sensor | w_->stuck_on | encoder_invalid_) & axis_bit(a))) continue;
    const double latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
    const double to_end = (*far_end(s, c) - r_.actual(a)) * -dir_of(s);
    // (A limit switch's measurement may raise max_seek_travel to reach it.)
    const double travel = std::min(to_end + measure_lag_mm(a), s.limits_fitted ? 1e300 : s.max_seek_travel_mm);
    if (travel / latch_v <= kMeasureBudget_s) measurable.push_back(a);
  }
  const bool home_all_only = measure_acts_.chance(0.1);
  const bool two = measure_acts_.chance(0.1);
  if (home_all_only || two || measurable.empty() || measure_acts_.chance(0.3)) {
    if (refused.empty() && !home_all_only && !two) return;
    AxisMask mask = 0;
    if (!refused.empty() && !home_all_only && !two) {
      mask = axis_bit(refused[static_cast<std::size_t>(measure_acts_.integer(0, static_cast<int>(refused.size()) - 1))]);
    } else {
      mask = axis_bit(static_cast<std::size_t>(measure_acts_.integer(0, kAxisCount - 1)));
      if (two) mask |= axis_bit(static_cast<std::size_t>(measure_acts_.integer(0, kAxisCount - 1)));
    }
    measure_refused(mask, home_all_only);
    return;
  }
  measure_axis(measurable[static_cast<std::size_t>(measure_acts_.integer(0, static_cast<int>(measurable.size()) - 1))]);
}

// A measurement the docs refuse: the result they name, and nothing moves.
void Run::measure_refused(AxisMask mask, bool home_all_only) {
  if (!home_all_only && measure_expected(mask) == CommandResult::accepted) return;  // drew one axis twice
  if (home_all_only) {
    say("write global.single_axis_homing = 0");
    r_.settings.global.single_axis_homing = false;
    w_->settings_changed();
  }
  const CommandResult expected = measure_expected(mask);
  say("measure " + axis_letters(mask) + " (the docs refuse it: " + std::string(command_result_name(expected)) + ")");
  std::array<double, kAxisCount> x0{};
  for (std::size_t a = 0; a < kAxisCount; ++a) x0[a] = r_.actual(a);
  w_->clear_alarms_seen();
  r_.pending.measure_axes = mask;
  step();
  const CommandResult res = r_.status().last_command_result;
  for (int i = 0; i < 5 && ok(); ++i) step();
  if (res != expected)
    w_->fail("a measurement was not refused as the docs say",
             axis_letters(mask) + ": " + std::string(command_result_name(res)) + ", expected " +
                 std::string(command_result_name(expected)));
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (r_.actual(a) != x0[a] || r_.status().homing)
      w_->fail("a refused measurement moved an axis", std::string(1, kAxisUpper[a]) + " from " + fig(x0[a]) + " to " +
                                                          fig(r_.actual(a)));
  if (w_->alarms_seen) w_->fail("a refused measurement raised an alarm", alarm_list(w_->alarms_seen));
  if (home_all_only) {
    r_.settings.global.single_axis_homing = true;
    w_->settings_changed();
    step();
  }
  mark("measurement refused: " + std::string(command_result_name(expected)), seen::present);
}

// A measurement the docs accept: a single-axis cycle (cycle() judges its
// homing as any other), then the travel to the far end, judged here.
void Run::measure_axis(std::size_t a) {
  const AxisSettings& s = r_.settings.axes[a];
  const sim::AxisConfig& c = r_.sim().axis_config(a);
  const bool by_limit = s.limits_fitted;
  const std::string row = by_limit ? "measurement to a limit switch" : "measurement to a hard stop";
  const std::string x(1, kAxisUpper[a]);
  // A far end beyond max_seek_travel: mostly raised first, as the alarm's
  // text advises (kept: a seek from the far end needs it too).
  const double to_end = std::abs(*far_end(s, c) - r_.actual(a));
  const double wanted = std::ceil(to_end + s.pull_off_mm + s.max_backoff_mm +
                                  std::abs(s.final_position_mm - s.home_position_mm) + measure_lag_mm(a) + 10);
  // (Not past a cam shorter than the seek's stop: the seek would run on to
  // the limit switch beyond it, where max_seek_travel stopped it before.)
  if (by_limit && wanted > s.max_seek_travel_mm && measure_acts_.chance(0.7) && !m_.plan[a].short_cam) {
    const double old = s.max_seek_travel_mm;
    r_.settings.axes[a].max_seek_travel_mm = wanted;
    if (first_fault(r_.settings)) {
      r_.settings.axes[a].max_seek_travel_mm = old;
    } else {
      say("write " + x + ".max_seek_travel = " + fig(wanted) + " for the measurement");
      w_->settings_changed();
      step();
    }
  }
  measuring_ = MeasureRun{};
  measuring_->axis = a;
  measuring_->end = *far_end(s, c);
  const std::uint32_t cycles_before = r_.status().homing_cycles;
  const bool clean = cycle(false, axis_bit(a), {}, false, axis_bit(a));
  const MeasureRun mr = *measuring_;
  measuring_.reset();
  // Its travel ends beyond the soft limits, where a cycle may leave it.
  w_->outside_soft_limits |= axis_bit(a);
  if (!ok()) return;
  mark(row, static_cast<std::uint8_t>(seen::present | (w_->alarms_seen ? seen::alarmed : 0)));
  if (!clean) {
    // Explained by the cycle's verdict: a cause of the homing, or the end beyond max_seek_travel.
    if (w_->axis_alarms[a] & alarm_bit(AlarmCode::travel_end_not_found)) mark("measurement: no end within max_seek_travel", seen::alarmed);
    // Stopped on its way to the far end, where no cycle of this machine
    // starts (a pre-move away from home would run into that end, seed
    // 187202370): the technician resets, puts it back by hand and unhomes it.
    if (r_.status().alarm) recover();
    if (ok() && !r_.status().alarm && std::abs(r_.actual(a) - m_.sim.axes[a].actual_position_mm) > 0) {
      put_back(axis_bit(a));
      say("unhome " + x + ", moved by hand");
      r_.pending.unhome_axes |= axis_bit(a);
      step();
    }
    return;
  }
  if (!mr.began) {
    w_->fail("a measurement ended without an alarm and never travelled to its end", x);
    return;
  }
  if (r_.status().homing_cycles != cycles_before + 1)
    w_->fail("a measurement was not counted as a homing cycle", std::to_string(r_.status().homing_cycles));
  const double toward = -dir_of(s);
  const Measurement& got = r_.axis(a).measurement;
  const double lag = measure_lag_mm(a);
  if (mr.offset_valid) {
    // The usable travel the machine really has: from the home position to
    // the end where the simulator has it, less the stop from jog feedrate.
    const double jog_v = mm_per_min_to_mm_per_s(s.jog_feedrate_mm_per_min);
    const double jog_stop = stop_distance_mm(jog_v, s.acceleration_mm_per_s2);
    const double end_machine = mr.end + mr.offset;
    const double usable = (end_machine - s.home_position_mm) * toward - jog_stop;
    // Reads long by the lag at most, never short (the truth's own tolerance aside).
    const double err = got.usable_travel_mm - std::max(0.0, usable);
    const double tol = mr.tol + 1e-6;
    std::ostringstream o;
    o << x << " measured usable travel " << got.usable_travel_mm << ", the machine's " << usable << " (its "
      << (by_limit ? "limit switch" : "hard stop") << " at " << mr.end << ", offset " << mr.offset << "), may read long by "
      << lag;
    if (usable > 0 && (err < -tol || err > lag + tol)) w_->fail("the measured travel differs from the simulated machine's", o.str());
    // The suggested soft limits: the home position and the usable end.
    const double far = s.home_position_mm + toward * got.usable_travel_mm;
    if (std::abs(got.soft_limit_min_mm - std::min(s.home_position_mm, far)) > 1e-6 ||
        std::abs(got.soft_limit_max_mm - std::max(s.home_position_mm, far)) > 1e-6)
      w_->fail("the suggested soft limits are not the home position and the usable end",
               "[" + fig(got.soft_limit_min_mm) + ", " + fig(got.soft_limit_max_mm) + "] for travel " +
                   fig(got.usable_travel_mm));
    // The suggested max_seek_travel lets a seek from the far end reach where
    // the home end is told (the cam's edge, the home stop), and not much more.
    const double home_end = by_limit ? (dir_of(s) < 0 ? c.sensor_max_mm : c.sensor_min_mm)
                                     : (dir_of(s) < 0 ? c.hard_stop_min_mm : c.hard_stop_max_mm);
    const double seek = std::abs(mr.end - home_end);
    const double extra = c.hysteresis_mm + 4 * c.noise_mm + (s.mode == HomingMode::switch_index ? s.index_pitch_mm : 0) +
                         s.max_stop_distance_mm + lag + tol;
    const double most = std::ceil(seek + extra + std::max(0.1 * (seek + extra), 5.0)) + 1;
    if (got.max_seek_travel_mm < seek || got.max_seek_travel_mm > most)
      w_->fail("the suggested max_seek_travel does not fit the machine",
               x + ": " + fig(got.max_seek_travel_mm) + ", a seek from the far end needs " + fig(seek) + ", at most " +
                   fig(most));
  }
  const double xa = r_.actual(a);
  if (by_limit) {
    // Braked, left the switch at latch feedrate, still homed.
    if (!r_.axis(a).homed) w_->fail("a measurement to a limit switch left its axis unhomed", x);
    if (r_.sim().limit_active(a, toward > 0)) w_->fail("a measurement ended on the limit switch it found", x + " at " + fig(xa));
    if (std::abs(xa - mr.end) > s.max_backoff_mm + lag)
      w_->fail("a measurement ended further from its limit switch than max_backoff", x + " at " + fig(xa) + ", switch at " +
                                                                                        fig(mr.end));
  } else {
    // Steps lost against the stop: unhomed, pull-off away from it (and a
    // pre-move that always runs: the home cycle that follows makes it first).
    if (r_.axis(a).homed) w_->fail("a measurement that pushed into a hard stop left its axis homed", x);
    const double pre_move = s.pre_move_mode == PreMove::always ? s.pre_move_distance_mm : 0;
    const double rest = mr.end - toward * (s.pull_off_mm + pre_move);
    if (std::abs(xa - rest) > 1e-6)
      w_->fail("a measurement did not end pull-off (and a pre-move) away from the hard stop", x + " at " + fig(xa) + ", expected " + fig(rest));
  }
  // Nothing written: the soft limits the engine enforces are still the
  // configured ones, whatever the measurement suggested.
  if (ok() && r_.axis(a).homed && s.soft_limits_enable && !r_.status().alarm) {
    const double limit = toward > 0 ? s.soft_limit_max_mm : s.soft_limit_min_mm;
    const double target = limit + toward * 0.5;
    say(std::string("move ") + x + " to " + fig(target) + ", past its configured soft limit");
    const double x0 = r_.actual(a);
    r_.move(a, target);
    const CommandResult res = r_.status().last_command_result;
    for (int i = 0; i < 3; ++i) step();
    if (res != CommandResult::refused_soft_limit || r_.actual(a) != x0)
      w_->fail("after a measurement a move past the configured soft limit was not refused",
               x + ": " + std::string(command_result_name(res)) + ", moved " + fig(r_.actual(a) - x0));
  }
  if (ok()) {
    mark(row, seen::homed);  // judged against the machine
    acts_ |= act::measured;
  }
}

// In every period of a measurement's cycle: the truth while the axis is
// homed, and, where its travel begins, whether the far end lies within
// max_seek_travel of there (docs: travel_end_not_found otherwise).
void Run::measure_period(Causes& causes) {
  if (!measuring_) return;
  MeasureRun& m = *measuring_;
  const std::size_t a = m.axis;
  if (m.began) return;
  if (r_.axis(a).phase != Phase::measure_travel) {
    m.x_last = r_.actual(a);
    m.offset_valid = w_->truth[a].valid;
    m.offset = w_->truth[a].offset;
    m.tol = w_->truth[a].tol;
    return;
  }
  m.began = true;
  const AxisSettings& s = r_.settings.axes[a];
  // The travel begins where the engine stood as it entered the phase: the
  // carriage at the end of the period before (within that period's travel).
  const double latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
  const double to_end = (m.end - m.x_last) * -dir_of(s);
  const double slack = latch_v * m_.max_dt_s + 1e-6;
  say(std::string(1, kAxisUpper[a]) + "'s measurement travels from " + fig(m.x_last) + ", its far end " + fig(to_end) +
      " away, max_seek_travel " + fig(s.max_seek_travel_mm));
  if (to_end + measure_lag_mm(a) + slack >= s.max_seek_travel_mm)
    causes.add(std::string(1, kAxisUpper[a]) + "'s far end beyond max_seek_travel from where its measurement travels",
               {AlarmCode::travel_end_not_found}, axis_bit(a), to_end > s.max_seek_travel_mm + slack)
        .kind = "measurement: the far end beyond max_seek_travel";
}

// --- a daemon restart and reference checks -----------------------------------

// The docs' refusals of a reference check, the lowest axis's first.
CommandResult Run::refcheck_expected(AxisMask mask, const std::array<bool, kAxisCount>& offered) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(mask & axis_bit(a))) continue;
    const AxisSettings& s = r_.settings.axes[a];
    if (s.mode == HomingMode::disabled) return CommandResult::refused_invalid;
    if (partner_index(r_.settings, a) >= 0) return CommandResult::refused_gantry_pair;
    if (!offers_check(s.mode)) return CommandResult::refused_no_switch_edge;
    if (!offered[a]) return CommandResult::refused_no_clean_stop;
  }
  return CommandResult::accepted;
}

// The daemon stopped (SIGTERM: the last stops kept; or killed: none clean)
// and started again: a new engine, every axis unhomed, given the last stops
// as homingd gives them; the simulated carriages stay where they are, some
// moved by hand meanwhile. Then reference checks, judged from where the
// carriages really are.
void Run::restart_with_checks() {
  if (!restarts_.chance(0.2)) return;
  if (r_.status().alarm || r_.status().homing || r_.any_moving() || comm_lost_ || r_.sim().inputs().estop) return;
  if (r_.settings.global.permit_required && !r_.sim().inputs().homing_permit) return;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (r_.sim().axis_config(a).fault != sim::Fault::none || on_limit_switch(a) || r_.sim().moving(a) ||
        r_.axis(a).phase == Phase::unlock || r_.axis(a).phase == Phase::lock)
      return;
  const bool killed = restarts_.chance(0.15);
  // What homingd keeps at a clean stop (homing/last_stop.cpp, the daemon's
  // own rule), held to the docs: clean = homed, at rest, drive enabled, no alarm.
  LastStops stops = last_stops_at_shutdown(r_.settings, r_.status(), r_.engine.outputs());
  // (A disabled axis reads homed whether or not a cycle covered it, and its
  // stop is never offered a check: not judged.)
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (r_.settings.axes[a].mode != HomingMode::disabled && stops[a].clean != r_.axis(a).homed)
      w_->fail("the last stops kept at a clean shutdown are not those the docs call clean",
               std::string(1, kAxisUpper[a]) + (r_.axis(a).homed ? " homed at rest, not clean" : " not homed, clean"));
  if (killed)
    for (LastStop& st : stops) st.clean = false;  // homingd wiped the marks at start; nothing wrote them again
  const std::array<Truth, kAxisCount> truth = w_->truth;
  std::array<bool, kAxisCount> homed{};
  for (std::size_t a = 0; a < kAxisCount; ++a) homed[a] = homed_axis(a);
  say(killed ? "the daemon is killed and started again: no clean stop recorded"
             : "the daemon stops (SIGTERM) and starts again; clean stops: " + [&] {
                 AxisMask m = 0;
                 for (std::size_t a = 0; a < kAxisCount; ++a)
                   if (stops[a].clean) m |= axis_bit(a);
                 return axis_letters(m);
               }());
  r_.engine = Engine{};
  r_.pending = Commands{};
  r_.held = Commands{};
  // Carriages moved by hand while the daemon was off, on axes a check may
  // home: within the tolerance or well beyond it, never onto a limit switch
  // or a stop, nor within a pre-move of one (no cycle of the machine starts
  // there: seed 187204642), nor across a cam.
  std::array<double, kAxisCount> moved{};
  AxisMask by_hand = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisSettings& s = r_.settings.axes[a];
    const sim::AxisConfig& c = r_.sim().axis_config(a);
    if (m_.plan[a].role != Role::plain || partner_index(r_.settings, a) >= 0 || !offers_check(s.mode) ||
        !restarts_.chance(0.3))
      continue;
    const double tol = s.refcheck_tolerance_mm;
    const double slack = refcheck_slack_mm(a);
    double d = restarts_.chance(0.4) ? restarts_.u(0, 0.5 * tol) : tol + 2 * slack + restarts_.u(0.01, 3);
    d *= restarts_.sign();
    if (c.sensor_max_mm > c.sensor_min_mm) d = std::clamp(d, -0.4 * (c.sensor_max_mm - c.sensor_min_mm), 0.4 * (c.sensor_max_mm - c.sensor_min_mm));
    const double x = r_.actual(a) + d;
    const double margin = 0.5 + (s.pre_move_mode != PreMove::none ? s.pre_move_distance_mm : 0);
    const double lo = std::max(c.hard_stop_min_mm, s.limits_fitted ? c.limit_min_mm : -1e300) + margin;
    const double hi = std::min(c.hard_stop_max_mm, s.limits_fitted ? c.limit_max_mm : 1e300) - margin;
    if (x < lo || x > hi || !r_.sim().place(a, x)) continue;
    moved[a] = d;
    by_hand |= axis_bit(a);
  }
  // The daemon is off a while: the simulator runs on with nothing commanded,
  // so its inputs show the carriages where the hand left them (the
  // simulator reads its switches as it advances; a new engine would take
  // the old levels for the machine's, and their change for an edge).
  const Outputs off{};
  for (int i = 0; i < 20; ++i) r_.sim().advance(off, 0.001);
  if (by_hand) {
    std::ostringstream o;
    o << "moved by hand while it was off:";
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (by_hand & axis_bit(a)) o << " " << kAxisUpper[a] << " by " << moved[a];
    say(o.str());
    w_->carriages_placed();
  }
  // (Racked pairs: seed 187207148, a gantry an alarm left racked, then the restart.)
  AxisMask homed_mask = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (homed[a]) homed_mask |= axis_bit(a);
  w_->restarted(homed_mask);
  r_.restore = stops;
  step();
  // Every axis unhomed; those with a clean stop trust it and show the stored position.
  std::array<bool, kAxisCount> offered{};
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisStatus& as = r_.axis(a);
    const std::string x(1, kAxisUpper[a]);
    offered[a] = stops[a].clean && r_.settings.axes[a].mode != HomingMode::disabled;
    if (as.homed && r_.settings.axes[a].mode != HomingMode::disabled) w_->fail("an axis was homed right after a restart", x);
    const Trust want = offered[a] ? Trust::last_stop_clean : Trust::unknown;
    if (as.trust != want)
      w_->fail("after a restart an axis's trust is not what its last stop gives",
               x + ": " + std::string(name_of(as.trust)) + ", expected " + std::string(name_of(want)));
    else if (offered[a] && std::abs(as.position_mm - stops[a].position_mm) > 1e-6)
      w_->fail("after a restart an axis does not show its stored position",
               x + ": " + fig(as.position_mm) + ", stored " + fig(stops[a].position_mm));
  }
  mark(killed ? "restart after a kill" : "restart after a clean stop", seen::present);
  if (!ok()) return;
  // A check the docs refuse moves nothing and withdraws no offer.
  std::vector<std::size_t> refused, checkable;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (refcheck_expected(axis_bit(a), offered) != CommandResult::accepted) refused.push_back(a);
    else if (!m_.plan[a].cam_at_limit) checkable.push_back(a);  // its limit switch lies within the latch
  }
  if (!refused.empty() && (checkable.empty() || restarts_.chance(0.5))) {
    const std::size_t a = refused[static_cast<std::size_t>(restarts_.integer(0, static_cast<int>(refused.size()) - 1))];
    refcheck_refused(axis_bit(a), offered);
  }
  if (!ok() || checkable.empty()) return;
  AxisMask mask = 0;
  for (const std::size_t a : checkable)
    if (restarts_.chance(0.8)) mask |= axis_bit(a);
  if (mask) refcheck(mask, truth, homed, moved);
}

// The reference edge's own uncertainty between the cycle that homed the axis
// and the check: the sensor's noise (each edge within 4 sigma, the cycle's
// median of latch passes and the check's one pass), the edge's timing error
// at latch feedrate in a late period, and the arithmetic.
double Run::refcheck_slack_mm(std::size_t a) {
  const AxisSettings& s = r_.settings.axes[a];
  return 8 * r_.sim().axis_config(a).noise_mm + 2 * rig::edge_tolerance_mm(s, m_.max_dt_s) + 2e-3;
}

void Run::refcheck_refused(AxisMask mask, const std::array<bool, kAxisCount>& offered) {
  const CommandResult expected = refcheck_expected(mask, offered);
  say("reference check of " + axis_letters(mask) + " (the docs refuse it: " + std::string(command_result_name(expected)) + ")");
  std::array<double, kAxisCount> x0{};
  std::array<Trust, kAxisCount> trust0{};
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    x0[a] = r_.actual(a);
    trust0[a] = r_.axis(a).trust;
  }
  w_->clear_alarms_seen();
  r_.pending.refcheck_axes = mask;
  step();
  const CommandResult res = r_.status().last_command_result;
  for (int i = 0; i < 5 && ok(); ++i) step();
  if (res != expected)
    w_->fail("a reference check was not refused as the docs say", axis_letters(mask) + ": " +
                                                                      std::string(command_result_name(res)) + ", expected " +
                                                                      std::string(command_result_name(expected)));
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (r_.actual(a) != x0[a]) w_->fail("a refused reference check moved an axis", std::string(1, kAxisUpper[a]));
    if (r_.axis(a).trust != trust0[a])
      w_->fail("a refused reference check changed an axis's trust", std::string(1, kAxisUpper[a]) + ": " +
                                                                        std::string(name_of(r_.axis(a).trust)));
  }
  if (w_->alarms_seen) w_->fail("a refused reference check raised an alarm", alarm_list(w_->alarms_seen));
  mark("reference check refused: " + std::string(command_result_name(expected)), seen::present);
}

// Checks the docs accept: each axis homed when its edge lies within
// refcheck_tolerance of where the stored position puts it, refused with the
// mismatch when its carriage was moved further; back where it started.
void Run::refcheck(AxisMask mask, const std::array<Truth, kAxisCount>& truth, const std::array<bool, kAxisCount>& homed,
                   const std::array<double, kAxisCount>& moved) {
  // Movers, not covered: the watch's flip to homed takes the last edge of
  // the window, and a home cam's way back may cross its cam again; the
  // truth of an accepted check is set below, from the cycle before.
  CyclePlan plan;
  plan.movers = mask;
  double bound_s = 5;
  std::array<double, kAxisCount> x0{};
  std::array<bool, kAxisCount> on_sensor{};
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    x0[a] = r_.actual(a);
    on_sensor[a] = r_.sim().sensor_active(a);
    if (!(mask & axis_bit(a))) continue;
    plan.step[a] = 1;  // one step holding every axis checked
    const AxisSettings& s = r_.settings.axes[a];
    // From where it stands (its stored position, from the home position at
    // the rest point, and the hand's move) to the edge, past it by the
    // search's bound, off the switch and back: at latch feedrate at the
    // slowest.
    const double latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
    const double path = std::abs(r_.axis(a).position_mm - s.home_position_mm) + std::abs(moved[a]) + s.pull_off_mm +
                        s.refcheck_tolerance_mm + s.max_stop_distance_mm +
                        2 * s.max_backoff_mm + r_.sim().axis_config(a).hysteresis_mm + 1;
    bound_s = std::max(bound_s, 2 * path / latch_v + 5 + (s.indexer_lock ? 2 * s.lock_timeout_ms / 1000 : 0));
  }
  say("reference check of " + axis_letters(mask));
  const std::uint32_t cycles_before = r_.status().homing_cycles;
  w_->clear_alarms_seen();
  w_->begin_window(plan, false);
  r_.pending.refcheck_axes = mask;
  step();
  const CommandResult res = r_.status().last_command_result;
  if (res != CommandResult::accepted) w_->fail("a reference check the docs accept was refused", std::string(command_result_name(res)));
  r_.run_until([&] { return !r_.status().homing || !ok(); }, bound_s);
  if (r_.status().homing && ok()) w_->fail("a reference check did not end within its bound", fig(bound_s) + " s");
  settle(10);
  w_->end_window();
  if (!ok()) return;
  // An axis whose stored position the truth no longer vouches for (steps
  // lost since its cycle) may search past where its edge really is, as far
  // as the stored position bounds it, into its limit switch: the one alarm
  // excused (seeds 187300765, 187303014).
  AxisMask excused = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const bool known = homed[a] && truth[a].valid && truth[a].has_rest;
    if ((mask & axis_bit(a)) && !known && r_.settings.axes[a].limits_fitted &&
        w_->axis_alarms[a] == alarm_bit(AlarmCode::limit_in_homing))
      excused |= axis_bit(a);
  }
  bool unexplained = w_->global_alarms != 0;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (w_->axis_alarms[a] && !(excused & axis_bit(a))) unexplained = true;
  if (unexplained) {
    std::string where;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (w_->axis_alarms[a]) where += std::string(" ") + kAxisUpper[a] + ": " + alarm_list(w_->axis_alarms[a]) + " (" + describe_alarm(a, w_->first_alarm[a], r_.settings) + ")";
    if (w_->global_alarms) where += " global: " + alarm_list(w_->global_alarms);
    w_->fail("an alarm during a reference check of a machine in order", alarm_list(w_->alarms_seen) + ";" + where);
    return;
  }
  if (excused) {
    mark("reference check of a carriage not where stored, into its limit switch", seen::alarmed);
    return;  // the next act recovers
  }
  if (r_.status().homing_cycles != cycles_before) w_->fail("a reference check was counted as a homing cycle");
  for (std::size_t a = 0; a < kAxisCount && ok(); ++a) {
    if (!(mask & axis_bit(a))) continue;
    const AxisSettings& s = r_.settings.axes[a];
    const AxisStatus& as = r_.axis(a);
    const std::string x(1, kAxisUpper[a]);
    const double tol = s.refcheck_tolerance_mm;
    const double slack = refcheck_slack_mm(a);
    const bool accepted = as.homed;
    const bool known = homed[a] && truth[a].valid && truth[a].has_rest;  // where its stored position put the edge is known
    const double d = moved[a];
    std::ostringstream o;
    o << x << " moved by hand by " << d << ", tolerance " << tol << " (slack " << slack << "), mismatch "
      << as.refcheck_error_mm << ", carriage " << r_.actual(a) << " from " << x0[a] << ", position " << as.position_mm;
    say("reference check of " + x + (accepted ? " accepted" : " refused") + ": mismatch " + fig(as.refcheck_error_mm));
    if (known && !accepted && std::abs(d) + slack < tol)
      w_->fail("a reference check refused a carriage within its tolerance of its stored place", o.str());
    if (known && accepted && std::abs(d) - slack > tol)
      w_->fail("a reference check accepted a carriage moved by hand beyond its tolerance", o.str());
    if (accepted) {
      if (as.trust != Trust::reference_checked) w_->fail("an axis homed by a reference check does not say so", x + ": " + std::string(name_of(as.trust)));
      if (std::abs(as.refcheck_error_mm) > tol + 1e-9) w_->fail("an accepted reference check reports a mismatch beyond its tolerance", o.str());
      // Its coordinate is the machine's where the carriage really stands
      // (the frame the cycle before the restart found), within the
      // tolerance: the watch holds it to the edge just found.
      // Its coordinate is taken from the edge just found (a hand's move
      // within the tolerance corrected): the machine's where the carriage
      // really stands, as the cycle before the restart found its frame,
      // within that edge's own uncertainty. From here the watch holds it there.
      if (known) {
        const double error = as.position_mm - (r_.actual(a) + truth[a].offset);
        if (std::abs(error) > truth[a].tol + slack) {
          w_->fail("a reference check homed an axis away from its true position",
                   o.str() + ", true " + fig(r_.actual(a) + truth[a].offset));
        } else {
          Truth t = truth[a];
          t.tol += slack;
          w_->truth[a] = t;
        }
      }
      if (on_sensor[a] && known && std::abs(r_.actual(a) - truth[a].rest) > truth[a].tol + slack)
        w_->fail("an accepted reference check that started on its switch did not end pull-off away from the edge",
                 o.str() + ", rest point " + fig(truth[a].rest));
      // A shared limit that started nearer its edge than its rest point ends
      // at the rest point too (docs): the hysteresis may hold its switch there.
      const bool at_rest = known && std::abs(r_.actual(a) - truth[a].rest) <= truth[a].tol + slack;
      if (!on_sensor[a] && std::abs(r_.actual(a) - x0[a]) > 1e-6 && !(s.shared_limit && (at_rest || !known)))
        w_->fail("a reference check did not go back where it started", o.str());
      // Homed where the hand left it, it may stand beyond its soft limits.
      w_->outside_soft_limits |= axis_bit(a);
    } else {
      if (as.trust != Trust::unknown) w_->fail("a refused reference check left its axis trusted", x + ": " + std::string(name_of(as.trust)));
      if (std::abs(r_.actual(a) - x0[a]) > 1e-6) w_->fail("a reference check did not go back where it started", o.str());
      // Moved less than the search reaches: the edge was found, as far off
      // as the hand moved the carriage (moved by +d, it is met d early in
      // the stored coordinates: the figure is -d). Beyond, the figure is as
      // far as the search went (docs), which may be less than the tolerance.
      const double past = tol + s.max_stop_distance_mm;
      const double reach = std::min(past, s.max_backoff_mm - r_.sim().axis_config(a).hysteresis_mm) - slack;
      // Moved off the far side of the switch (in the seek's direction) from
      // on it: the check meets the switch's other edge, not the one it stored,
      // and its figure is that edge's (seed 191006514 of the release run:
      // left 1 mm inside a 2.9 mm cam, moved 1.17 mm out of its far side).
      const auto& cfg = r_.sim().axis_config(a);
      const double stored_x = x0[a] - d;
      const bool cam = cfg.sensor_max_mm >= cfg.sensor_min_mm;
      const auto beyond_far = [&](double x) {
        return dir_of(effective(r_.settings, a)) > 0 ? x > cfg.sensor_max_mm : x < cfg.sensor_min_mm;
      };
      const bool crossed_far_edge = cam && !beyond_far(stored_x) && beyond_far(x0[a]);
      if (known && !crossed_far_edge && std::abs(d) < reach && std::abs(as.refcheck_error_mm + d) > slack)
        w_->fail("a refused reference check's mismatch is not how far the carriage was moved", o.str());
    }
    const bool beyond = std::abs(d) > tol;
    mark(std::string("reference check ") + (accepted ? "accepted" : "refused") +
             (beyond ? ", carriage moved by hand beyond the tolerance" : std::abs(d) > 0 ? ", carriage moved by hand within the tolerance" : ", carriage where it stopped"),
         static_cast<std::uint8_t>(seen::present | (known ? seen::homed : 0)));
    if (accepted && ok()) acts_ |= act::refchecked;
  }
}

}  // namespace campaign
