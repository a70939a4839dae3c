#include "verdict.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include "homing/motion.hpp"

namespace campaign {

AlarmBits code_bits(std::initializer_list<AlarmCode> codes) {
  AlarmBits bits = 0;
  for (AlarmCode c : codes) bits |= alarm_bit(c);
  return bits;
}

Cause& Causes::add(std::string what, std::initializer_list<AlarmCode> codes, AxisMask axes, bool must) {
  Cause c;
  c.what = std::move(what);
  // "X's cam..." and "drive fault on X" are one class for every axis.
  c.kind = c.what;
  if (c.kind.size() > 4 && c.kind.compare(1, 3, "'s ") == 0) c.kind = "an axis's " + c.kind.substr(4);
  else if (c.kind.size() > 2 && c.kind[1] == ' ' && std::isupper(static_cast<unsigned char>(c.kind[0])))
    c.kind = "an axis " + c.kind.substr(2);
  if (const auto on = c.kind.find(" on "); on != std::string::npos && on + 5 == c.kind.size()) c.kind.resize(on);
  c.codes = code_bits(codes);
  c.axes = axes;
  c.must = must;
  list.push_back(std::move(c));
  return list.back();
}

Cause& Causes::sensor_fault(std::string what, AxisMask axes, bool must) {
  return add(std::move(what),
             {AlarmCode::sensor_not_found, AlarmCode::overrun_during_stop, AlarmCode::stop_distance_exceeded,
              AlarmCode::not_released, AlarmCode::reapproach_not_found, AlarmCode::index_not_found,
              AlarmCode::misalignment, AlarmCode::slave_sensor_missing, AlarmCode::hard_limit},
             axes, must);
}

Cause& Causes::sensor_fault(std::string what, AxisMask axes, const Settings& s, bool must) {
  Cause& c = sensor_fault(std::move(what), axes, must);
  // A home cam that never shows searches on to the other limit switch; one
  // that never releases latches on toward a limit switch.
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((axes & axis_bit(a)) && s.axes[a].limits_fitted)
      c.codes |= code_bits({AlarmCode::cam_not_found, AlarmCode::limit_in_homing});
  return c;
}

bool Causes::any_must() const {
  return std::any_of(list.begin(), list.end(), [](const Cause& c) { return c.must; });
}

std::string alarm_list(AlarmBits bits) {
  std::string out;
  for (unsigned c = 1; c < kAlarmCodeCount; ++c)
    if (bits & alarm_bit(static_cast<AlarmCode>(c))) out += (out.empty() ? "" : ", ") + std::string(alarm_name(static_cast<AlarmCode>(c)));
  return out.empty() ? "none" : out;
}

std::string axis_letters(AxisMask m) {
  std::string out;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (m & axis_bit(a)) out += kAxisUpper[a];
  return out.empty() ? "-" : out;
}

namespace {

std::string letter(std::size_t a) { return std::string(1, kAxisUpper[a]); }

// The axis and its gantry partner: a cause on one side may stop the pair
// with an alarm on the other (racking is the slave's alarm).
AxisMask with_partner(const Settings& s, std::size_t a) {
  const int p = partner_index(s, a);
  return static_cast<AxisMask>(axis_bit(a) | (p >= 0 ? axis_bit(static_cast<std::size_t>(p)) : 0));
}

// Every axis linked to `a` by slave_of, either way (a refused group).
AxisMask slave_of_group(const Settings& s, std::size_t a) {
  AxisMask g = axis_bit(a);
  for (int round = 0; round < 3; ++round)
    for (std::size_t x = 0; x < kAxisCount; ++x) {
      const int named = static_cast<int>(s.axes[x].slave_of) - 1;
      if (named < 0 || named >= static_cast<int>(kAxisCount)) continue;
      const std::size_t n = static_cast<std::size_t>(named);
      if ((g & axis_bit(x)) || (g & axis_bit(n))) g |= static_cast<AxisMask>(axis_bit(x) | axis_bit(n));
    }
  return g;
}

std::string cause_list(const Causes& causes) {
  std::string out;
  for (const Cause& c : causes.list) {
    out += (out.empty() ? "" : "; ") + c.what + ": " + alarm_list(c.codes) + " on " + axis_letters(c.axes);
    if (c.global) out += ", global " + alarm_list(c.global);
    if (c.must) out += " (must show)";
  }
  return out.empty() ? "none" : out;
}

}  // namespace

// What a home cam's search must end in, from where the cycle finds it
// (docs/limit-switches.md): a dead cam sensor or no cam between the limit
// switches: cam_not_found, once the search has reversed at one switch and met
// the other; a cam sensor stuck active: the latch never releases
// (not_released, or limit_in_homing where a switch lies within max_backoff);
// limit switches that never trip with the cam behind: the search runs on
// into the stop, to sensor_not_found at max_seek_travel; a limit switch
// within the latch or pull-off: limit_in_homing.
void home_cam_causes(Causes& c, rig::Rig& r, const AxisSettings& e, std::size_t a, sim::Fault f) {
  const auto& cfg = r.sim().axis_config(a);
  const AxisMask bit = axis_bit(a);
  const auto add = [&](std::string what, std::initializer_list<AlarmCode> codes, AxisMask axes, bool must) {
    c.add(std::move(what), codes, axes, must).needs_true_sensor = true;
  };
  const bool dead = f == sim::Fault::sensor_stuck_inactive || (f == sim::Fault::wire_break && !e.sensor_nc);
  const bool stuck_on = f == sim::Fault::sensor_stuck_active || (f == sim::Fault::wire_break && e.sensor_nc);
  if (dead) add(letter(a) + "'s dead cam sensor", {AlarmCode::cam_not_found}, bit, true);
  if (stuck_on) add(letter(a) + "'s cam sensor stuck active", {AlarmCode::not_released, AlarmCode::limit_in_homing}, bit, true);
  if (f == sim::Fault::limits_dead && cam_lies_behind(r, e, a))
    add(letter(a) + "'s dead limit switches with its cam behind", {AlarmCode::sensor_not_found}, bit, true);
  if (f != sim::Fault::none) return;
  const bool between = cfg.sensor_max_mm >= cfg.sensor_min_mm && cfg.sensor_max_mm > cfg.limit_min_mm &&
                       cfg.sensor_min_mm < cfg.limit_max_mm;
  if (!between) {
    add(letter(a) + "'s cam beyond its limit switches", {AlarmCode::cam_not_found}, bit, true);
    return;
  }
  // Where the latch releases and the pull-off ends, against the switch on that side.
  const double side = e.cam_edge == CamEdge::ahead ? dir_of(e) : -dir_of(e);
  const double edge = side > 0 ? cfg.sensor_max_mm : cfg.sensor_min_mm;
  const double rest = edge + side * (cfg.hysteresis_mm + e.pull_off_mm);
  const double past = (rest - (side > 0 ? cfg.limit_max_mm : cfg.limit_min_mm)) * side;
  const double noise = 4 * cfg.noise_mm + 1e-3;
  if (past > -noise)
    add(letter(a) + "'s limit switch within its latch or pull-off", {AlarmCode::limit_in_homing}, bit, past > noise);
}

// A pre-move away from the sensor heading past the limit switch on that side
// (a jog left the carriage next to it) must stop there with limit_in_homing;
// within a hair of the switch, or where the sensor decides whether it runs,
// it may. (A final move past a switch: Run::final_move_into_limit.)
void pre_move_cause(Causes& c, rig::Rig& r, const AxisSettings& e, std::size_t a) {
  const auto& cfg = r.sim().axis_config(a);
  const bool always = e.pre_move_mode == PreMove::always;
  if (!always && !(e.pre_move_mode == PreMove::if_sensor_active && r.sim().sensor_active(a))) return;
  const double away = -dir_of(e);
  const double target = r.actual(a) + away * e.pre_move_distance_mm;
  const double past = (target - (away > 0 ? cfg.limit_max_mm : cfg.limit_min_mm)) * away;
  if (past > -0.01)
    c.add(letter(a) + "'s pre-move past its limit switch", {AlarmCode::limit_in_homing}, axis_bit(a), past > 0.01 && always);
}

// A pre-move "always" that starts nearer the far stop than its own length
// presses into that stop (the watch excuses the touch: watch.cpp); a drive
// whose stall input reports it may still report it as the push toward the
// home stop begins (seed 194020875: a measurement's end, a cycle stopped
// after its pre-move, then the next pre-move 2.98 mm with 1.84 mm left).
void pre_move_into_stop_cause(Causes& c, rig::Rig& r, const AxisSettings& e, std::size_t a) {
  const auto& cfg = r.sim().axis_config(a);
  if (pre_move_meets_far_stop(e, r.actual(a), cfg.hard_stop_min_mm, cfg.hard_stop_max_mm))
    c.add(letter(a) + "'s pre-move into its far stop", {AlarmCode::stall_at_start}, axis_bit(a));
}

// How far a gantry's squaring goes beyond what its guard allows, as a skew
// of a pair that started square would: the correction `needed` (carriages,
// from where the cycle finds them) may take a pair found `rack` out of square
// back to square and up to the limit beyond, or keep it out on its own side.
double squaring_beyond(double needed, double rack, double limit) {
  if (rack < 0) {
    needed = -needed;
    rack = -rack;
  }
  if (needed <= 0) return std::max(0.0, -needed - rack);
  return needed + std::min(rack, limit);
}

Causes standing_causes(rig::Rig& r, const Machine& m, const CyclePlan& plan, bool refused, AxisMask encoder_invalid,
                       const std::array<std::optional<double>, kAxisCount>& rack) {
  Causes c;
  if (refused) {
    Cause& k = c.add(std::string("the configuration check's refusal (") + invalid_name(m.invalid) + " on " + letter(m.invalid_axis) + ")",
                     {AlarmCode::settings_fault, AlarmCode::slave_sensor_missing}, slave_of_group(r.settings, m.invalid_axis), true);
    k.kind = "the configuration check's refusal";
    return c;
  }
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisMask bit = axis_bit(a);
    const AxisPlan& p = m.plan[a];
    const bool mover = plan.movers & bit;
    const AxisSettings e = effective(r.settings, a);
    const sim::Fault f = r.sim().axis_config(a).fault;
    if (f == sim::Fault::sensor_stuck_active || f == sim::Fault::sensor_stuck_inactive || f == sim::Fault::wire_break)
      c.sensor_fault(letter(a) + "'s faulty sensor", with_partner(r.settings, a), r.settings, mover && mode_uses_switch(e.mode));
    if (p.short_cam) {
      // It must overrun only if the seek meets the cam fast enough: a seek
      // that starts close to it may still be accelerating (seed 1935).
      const auto& cfg = r.sim().axis_config(a);
      const double edge = dir_of(e) < 0 ? cfg.sensor_max_mm : cfg.sensor_min_mm;
      const double run_up = std::abs(edge - r.actual(a)) + (e.pre_move_mode == PreMove::always ? e.pre_move_distance_mm : 0);
      const double v_cam = std::min(mm_per_min_to_mm_per_s(e.seek_feedrate_mm_per_min),
                                    std::sqrt(2 * e.acceleration_mm_per_s2 * run_up));
      const bool overruns = stop_distance_mm(v_cam, e.acceleration_mm_per_s2) > cfg.sensor_max_mm - cfg.sensor_min_mm + cfg.hysteresis_mm;
      c.add(letter(a) + "'s cam shorter than its stop", {AlarmCode::overrun_during_stop, AlarmCode::sensor_not_found}, bit,
            mover && overruns);
    }
    // Hard-stop homing: a stall output that never comes or is on all the
    // time, or a stop further than the push reaches (README). An axis that
    // tells its stop by its encoder (docs/homing-methods.md) reads no stall
    // input: it needs the stop within the push's reach less its limit.
    if (mover && e.mode == HomingMode::hard_stop) {
      const bool by_encoder = e.stall_detect == StallDetect::following_error;
      if (f == sim::Fault::stall_dead && !by_encoder)
        c.add(letter(a) + "'s dead stall output", {AlarmCode::stop_not_found, AlarmCode::stall_timeout}, bit, true);
      if (f == sim::Fault::stall_stuck && !by_encoder)
        c.add(letter(a) + "'s stall output stuck on", {AlarmCode::stall_at_start}, bit, true);
      const auto& cfg = r.sim().axis_config(a);
      const double stop = dir_of(e) < 0 ? cfg.hard_stop_min_mm : cfg.hard_stop_max_mm;
      const double reach = e.max_seek_travel_mm - (e.pre_move_mode == PreMove::always ? e.pre_move_distance_mm : 0);
      const double gap = std::abs(r.actual(a) - stop);
      // Near the end of the reach the stall's detection time decides; the
      // encoder's resolution and noise decide when the lag passes the limit.
      const double settled = by_encoder ? 2 * (cfg.encoder_resolution_mm + 5 * cfg.encoder_noise_mm) + 1e-3 : 1e-3;
      // The steps needed until the stop is told (or the reversal shows):
      // lo and hi differ only where two outcomes are equally likely.
      double needed_lo = gap;
      double needed_hi = gap;
      const bool reversed = by_encoder && f == sim::Fault::encoder_reversed;
      if (by_encoder && !reversed) needed_lo = needed_hi = gap + e.max_following_error_mm;
      if (reversed) {
        // A reversed encoder counts the travel as lag: a carriage more than a
        // quarter of the limit from the stop shows the reversal after that
        // quarter; one closer rests on the stop, and the limit is passed
        // after the limit less the gap (seed 2258828930).
        const double quarter = 0.25 * e.max_following_error_mm;
        const double shows = quarter;
        const double passes = e.max_following_error_mm - gap;
        needed_lo = gap > quarter + settled ? shows : gap < quarter - settled ? passes : std::min(shows, passes);
        needed_hi = gap > quarter + settled ? shows : gap < quarter - settled ? passes : std::max(shows, passes);
        c.add(letter(a) + "'s reversed encoder", {AlarmCode::encoder_reversed}, bit,
              gap > quarter + settled && needed_hi < reach - 1);
      }
      if (needed_hi > reach - 1)
        c.add(letter(a) + "'s stop beyond the push's reach", {AlarmCode::stop_not_found, AlarmCode::stall_timeout}, bit,
              needed_lo > reach + settled);
    }
    if (p.rest_on_sensor) c.add(letter(a) + "'s shared limit resting on its sensor", {AlarmCode::settings_fault, AlarmCode::not_released}, bit);
    // A cycle that starts deeper in the cam than max_backoff can release (a
    // jog or move left it there) backs off straight away and must give up.
    // So does one that starts just past the cam's far side, within its
    // hysteresis, the sensor still active: its back-off crosses the whole cam
    // (seed 4661283270: a bump left the axis 0.014 mm past a 4.1 mm cam).
    if (mover && mode_uses_switch(e.mode) && f == sim::Fault::none) {
      const auto& cfg = r.sim().axis_config(a);
      const double x = r.actual(a);
      // The back-off leaves the cam away from direction; a home cam's latch toward its cam_edge side.
      const double away = e.mode == HomingMode::home_cam && e.cam_edge == CamEdge::ahead ? dir_of(e) : -dir_of(e);
      const double depth = away > 0 ? cfg.sensor_max_mm - x : x - cfg.sensor_min_mm;
      const double held = cfg.hysteresis_mm + 4 * cfg.noise_mm;  // past an edge by less, it may still read active
      const bool inside = x >= cfg.sensor_min_mm - held && x <= cfg.sensor_max_mm + held;
      if (inside && depth + cfg.hysteresis_mm + 4 * cfg.noise_mm >= e.max_backoff_mm)
        c.add(letter(a) + " starting deeper in its cam than max_backoff releases", {AlarmCode::not_released}, with_partner(r.settings, a));
    }
    // A cycle that starts further from the cam than the seek reaches (each
    // cycle an alarm cut short after a pre-move "always" leaves it that much
    // further away: seed 8040760) must end in sensor_not_found, as README
    // says; near the end of the reach the trigger's detection delay decides.
    // (A home cam's search reverses at the limit switch: its travel covers both ways.)
    // A software-slaved slave seeks its own sensor beside its master, with the
    // master's max_seek_travel, from where the earlier cycles left it (seed
    // 190061984 of the release run: two pre-moves and a back-off took the
    // slave 0.1 mm beyond the reach its master still had).
    if (mover && mode_uses_switch(e.mode) && f == sim::Fault::none && (p.role != Role::slave || !p.commutator) &&
        e.mode != HomingMode::home_cam) {
      const auto& cfg = r.sim().axis_config(a);
      const double x = r.actual(a);
      const bool inside = x >= cfg.sensor_min_mm && x <= cfg.sensor_max_mm;
      const double gap = dir_of(e) > 0 ? cfg.sensor_min_mm - x : x - cfg.sensor_max_mm;
      // Beyond the switch's far side in the seek's direction (a hand moved it
      // there: seed 191006514 of the release run), the seek runs away from it.
      const double past_far = dir_of(e) > 0 ? x - cfg.sensor_max_mm : cfg.sensor_min_mm - x;
      if (!inside && cfg.sensor_max_mm >= cfg.sensor_min_mm && past_far > 0)
        c.add(letter(a) + " starting beyond its switch in the seek's direction", {AlarmCode::sensor_not_found},
              with_partner(r.settings, a));
      if (!inside && gap > 0) {
        const double seek_v = mm_per_min_to_mm_per_s(e.seek_feedrate_mm_per_min);
        const double reach = gap + (e.pre_move_mode == PreMove::always ? e.pre_move_distance_mm : 0.0);
        const double delay = seek_v * (e.debounce_ms / 1000.0 + m.max_dt_s) + 4 * cfg.noise_mm;
        if (reach > e.max_seek_travel_mm - delay)
          c.add(letter(a) + " starting beyond its seek's reach", {AlarmCode::sensor_not_found}, with_partner(r.settings, a),
                // A slave's pair may stop first for its racking (misalignment).
                reach > e.max_seek_travel_mm + 1e-3 && p.role != Role::slave);
      }
    }
    // An unsequenced shared-limit axis is assigned where it stands: on its sensor, that is a trip.
    if ((plan.unsequenced & bit) && r.settings.axes[a].shared_limit)
      c.add(letter(a) + " unsequenced on its shared-limit sensor", {AlarmCode::hard_limit}, bit);
    if (p.role == Role::slave && mover) {
      // The squaring from where this cycle starts (an earlier alarm may have
      // left the pair racked: it may square back).
      const std::size_t mi = static_cast<std::size_t>(p.partner);
      const double limit = r.settings.axes[a].max_misalignment_mm;
      const double needed = p.rest_rel_mm - (r.actual(a) - r.actual(mi));
      const double skew = rack[a] ? squaring_beyond(needed, *rack[a], limit) : std::abs(needed);
      // Certain only while both sensors tell the truth: a side's sensor that
      // lies during the cycle (a wire break read as a trigger) may square the
      // pair on an edge that is not there (seed 185003649).
      if (p.bad_skew || !rack[a] || skew > p.budget_mm + 1e-3)
        c.add(letter(a) + "'s skew beyond its max misalignment",
              {AlarmCode::misalignment, AlarmCode::not_released, AlarmCode::sensor_not_found, AlarmCode::slave_sensor_missing},
              static_cast<AxisMask>(bit | axis_bit(mi)), rack[a] && skew > limit + p.extras_mm)
            .needs_true_sensor = true;
      // The gantry guard looks two periods ahead (docs/homing-methods.md
      // "Gantries: racking"): once one side of a software-slaved pair has
      // found its sensor, the other, still seeking, is predicted on at seek
      // for two of the latest periods and then braking. Where that reaches
      // the limit, the guard may stop a pair that never racked (seed
      // 21040289: 112 mm/s, 15 ms periods, limit 4.93 mm).
      const AxisSettings pe = effective(r.settings, a);
      const double seek_v = mm_per_min_to_mm_per_s(pe.seek_feedrate_mm_per_min);
      const double look_ahead = stop_distance_mm(seek_v, pe.acceleration_mm_per_s2) + 2 * seek_v * m.max_dt_s;
      if (!p.commutator && skew + look_ahead > limit)
        c.add(letter(a) + "'s pair seeking faster than the gantry guard's look-ahead allows", {AlarmCode::misalignment},
              static_cast<AxisMask>(bit | axis_bit(mi)));
    }
    // A drive that homes itself: what its fault, or an answer after its
    // time limit, must raise when its step comes.
    if (e.mode == HomingMode::drive && (plan.covered & bit)) {
      const auto& cfg = r.sim().axis_config(a);
      if (f == sim::Fault::drive_never_answers || f == sim::Fault::drive_done_lost)
        c.add(letter(a) + "'s drive never reporting home done", {AlarmCode::drive_no_answer}, bit, true);
      if (f == sim::Fault::drive_answers_at_once)
        c.add(letter(a) + "'s drive answering at once", {AlarmCode::drive_answered_at_once}, bit, true);
      // Any drive that answers at all (whatever else is wrong with the axis,
      // such as an indexer that never locks once it is done) may answer late;
      // one that the stuck pin never lets start is the indexer's cause.
      const bool answers = f != sim::Fault::drive_never_answers && f != sim::Fault::drive_done_lost &&
                           f != sim::Fault::drive_answers_at_once && f != sim::Fault::indexer_stuck_locked;
      if (answers) {
        const double takes = std::abs(cfg.drive_home_position_mm - r.actual(a)) / (cfg.drive_speed_mm_per_min / 60) +
                             cfg.drive_answer_ms / 1000;
        // Within a few late periods of the limit either may happen.
        if (takes > e.drive_home_timeout_s - 0.1)
          c.add(letter(a) + "'s drive answering after its time limit", {AlarmCode::drive_no_answer}, bit,
                takes > e.drive_home_timeout_s + 0.1);
      }
    }
    // A locking indexer's fault from power-up: the first unlock of an axis
    // that moves in this cycle times out (stuck locked), or its first lock
    // after the cycle does (never locks).
    if (f == sim::Fault::indexer_stuck_locked)
      c.add(letter(a) + "'s indexer stuck locked", {AlarmCode::unlock_not_confirmed}, bit, mover && mode_uses_switch(e.mode));
    if (f == sim::Fault::indexer_never_locks)
      c.add(letter(a) + "'s indexer that never locks", {AlarmCode::lock_not_confirmed}, bit,
            mover && mode_uses_switch(e.mode));
    if (mover && e.mode == HomingMode::home_cam) home_cam_causes(c, r, e, a, f);
    if (mover && e.limits_fitted && f == sim::Fault::none && p.role == Role::plain && mode_uses_switch(e.mode) &&
        e.mode != HomingMode::home_cam)
      pre_move_cause(c, r, e, a);
    if (mover) pre_move_into_stop_cause(c, r, e, a);
    // Both limit switches stuck active: the axis may not move at all.
    if (f == sim::Fault::limits_stuck)
      c.add(letter(a) + "'s limit switches stuck active", {AlarmCode::both_limits_active}, bit,
            mover && e.limits_fitted);
    if ((encoder_invalid & bit) && mode_is_absolute(e.mode))
      c.add(letter(a) + "'s invalid absolute encoder", {AlarmCode::encoder_fault}, bit,
            (plan.covered & bit) || (plan.unsequenced & bit));
    // Hard-stop homing by the encoder reads it as the push begins.
    if ((encoder_invalid & bit) && e.mode == HomingMode::hard_stop && e.stall_detect == StallDetect::following_error)
      c.add(letter(a) + "'s invalid encoder for the stop", {AlarmCode::encoder_fault}, bit, mover);
  }
  return c;
}

void event_cause(Causes& c, const Event& e, const Settings& s, const Status& st, const CyclePlan& plan) {
  const std::string who = std::string(event_name(e.kind)) + " on " + letter(e.axis);
  // Axes the cycle still runs, and those moving now.
  AxisMask running = 0, moving = 0, moving_on = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisStatus& as = st.axes[a];
    if ((plan.covered & axis_bit(a)) && as.phase != Phase::done) running |= with_partner(s, a);
    // A jog or move held while its indexer unlocks shows phase unlock; in a
    // cycle an axis of the cycle in unlock is one of those running.
    const bool held = as.phase == Phase::unlock && !(plan.covered & axis_bit(a));
    const bool commanded = as.phase == Phase::jog || as.phase == Phase::move || held;
    if (as.velocity_mm_per_s != 0 || commanded) moving |= with_partner(s, a);
    // Still moving in the period that reads the event: a last crawl that
    // ends within half a millisecond at its acceleration may end in it, and
    // then there is nothing left to stop (seed 186002100: X's pull-off at
    // 0.05 mm/s, 51,000 mm/s²).
    if (std::abs(as.velocity_mm_per_s) > effective(s, a).acceleration_mm_per_s2 * 5e-4 || commanded)
      moving_on |= with_partner(s, a);
  }
  // Under return_to_start every axis of the cycle may still move (back)
  // after a failure: a lost link or a withdrawn permit may stop it then.
  const AxisMask may_go_back =
      s.global.failure_policy == FailurePolicy::return_to_start ? plan.covered : AxisMask{0};
  switch (e.kind) {
    case EventKind::abort:
      c.add("the abort", {AlarmCode::aborted}, running, running != 0);
      if (running == 0) c.aborted_quietly = true;
      break;
    case EventKind::estop: {
      // Every axis of the running cycle (those done with it too) and every one moving.
      Cause& k = c.add("the e-stop", {AlarmCode::emergency_stop}, static_cast<AxisMask>(plan.covered | moving), true);
      k.global = code_bits({AlarmCode::emergency_stop});
      break;
    }
    case EventKind::drive_fault: {
      Cause& k = c.add(who, {AlarmCode::drive_fault}, axis_bit(e.axis), true);
      k.phase_axis = e.axis;
      k.phase = k.phase_seen = st.axes[e.axis].phase;
      break;
    }
    case EventKind::stuck_active:
    case EventKind::stuck_inactive:
    case EventKind::wire_break: c.sensor_fault(who, with_partner(s, e.axis), s); break;
    case EventKind::comm_lost:
      // It stops motion: a carriage moving when it came must show it (one
      // arriving in that very period may end a jog or a failed cycle's way
      // back without it), and so must a cycle free of alarms, even at rest
      // between two of its moves (seed 908624361).
      c.add("the communication loss", {AlarmCode::communication_lost},
            static_cast<AxisMask>(running | moving | may_go_back),
            moving_on != 0 || (st.homing && !st.alarm && running != 0));
      break;
    case EventKind::permit_off:
      c.add("the permit withdrawn", {AlarmCode::permit_withdrawn}, static_cast<AxisMask>(running | may_go_back),
            s.global.permit_required && running != 0);
      break;
    case EventKind::drive_done_lost: {
      // Done already given (homed by its drive): the reference is lost;
      // still to come: the drive never answers. Must show only for an axis
      // this cycle homes by its drive.
      const bool mine = (plan.covered & axis_bit(e.axis)) && s.axes[e.axis].mode == HomingMode::drive;
      c.add(who, {AlarmCode::drive_reference_lost, AlarmCode::drive_no_answer}, axis_bit(e.axis), mine);
      break;
    }
    case EventKind::reset:
    case EventKind::home_again:
    case EventKind::indexer_stuck_locked:  // indexer_cause: it needs the indexer's state
    case EventKind::indexer_never_locks:
    case EventKind::count: break;
  }
}

void indexer_cause(Causes& c, const Event& e, const Settings& s, const Status& st, const CyclePlan& plan,
                   bool unlock_output, bool pin_in, bool motor_running) {
  const std::string who = std::string(event_name(e.kind)) + " on " + letter(e.axis);
  const AxisStatus& as = st.axes[e.axis];
  const AxisMask bit = axis_bit(e.axis);
  const bool locking = as.phase == Phase::lock;
  // Locked, in a later sequence step of this cycle: it will unlock to home.
  const bool to_move = (plan.covered & bit) && as.phase == Phase::waiting && mode_uses_switch(s.axes[e.axis].mode);
  // The engine's next period still reads the pin as it stands now (the fault
  // acts in the period that follows); it locks the pin in the one after.
  if (e.kind == EventKind::indexer_stuck_locked) {
    if (unlock_output && !pin_in) {
      // Out for motion: it drops in under the axis. Certain while the motor
      // still runs; an axis coming to rest in that period locks instead.
      if (motor_running) c.add(who, {AlarmCode::lock_engaged}, bit, true);
      else c.add(who, {AlarmCode::lock_engaged, AlarmCode::unlock_not_confirmed}, bit, false);
    } else if (unlock_output) {  // still in while unlocking: it never comes out, unless the
      // motion it unlocks for goes away first (seed 194064769, a final move of
      // zero length, before the engine stopped unlocking for one: it locked
      // again at once, the pin never left)
      c.add(who, {AlarmCode::unlock_not_confirmed}, bit, false);
    } else if (!pin_in) {        // locking, pin still out: in at once, unless a motion comes first
      c.add(who, {AlarmCode::unlock_not_confirmed, AlarmCode::lock_engaged}, bit, false);
    } else {                     // locked: the next unlock times out
      c.add(who, {AlarmCode::unlock_not_confirmed}, bit, to_move);
    }
    return;
  }
  // Never locks: a pin that is out, or comes out for the motion still to
  // come, stays out when the axis next rests. One still in while unlocking
  // may never come out: the motion it is unlocked for can go away first (seed
  // 193061989, a final move of zero length before the engine stopped
  // unlocking for one: it locked again at once, and the pin that never left
  // needed no lock).
  const bool out_now = (unlock_output || locking) && !pin_in;
  c.add(who, {AlarmCode::lock_not_confirmed}, bit, out_now || (to_move && !locking));
}

std::optional<Unexplained> explain(const Watch& w, const Causes& causes, const Settings& s) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    for (unsigned code = 1; code < kAlarmCodeCount; ++code) {
      const AlarmBits bit = alarm_bit(static_cast<AlarmCode>(code));
      if (!(w.axis_alarms[a] & bit)) continue;
      const bool explained = std::any_of(causes.list.begin(), causes.list.end(), [&](const Cause& c) {
        return (c.codes & bit) && (c.axes & axis_bit(a));
      });
      if (explained) continue;
      std::ostringstream o;
      o << describe_alarm(a, w.first_alarm[a], s) << " (phase " << phase_name(w.first_alarm[a].phase) << "); causes: " << cause_list(causes);
      return Unexplained{"alarm " + alarm_list(bit) + " without a cause on its axis", letter(a) + ": " + o.str()};
    }
  }
  if (const AlarmBits stray = w.global_alarms & ~[&] {
        AlarmBits g = 0;
        for (const Cause& c : causes.list) g |= c.global;
        return g;
      }())
    return Unexplained{"global alarm " + alarm_list(stray) + " without a cause", "causes: " + cause_list(causes)};
  for (const Cause& c : causes.list) {
    if (!c.must) continue;
    bool shown = (w.global_alarms & c.global) != 0;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if ((c.axes & axis_bit(a)) && (w.axis_alarms[a] & c.codes)) shown = true;
    // Another cause's alarm stopped the machine first (explained above):
    // this one never got to act.
    if (!shown && w.alarms_seen != 0) continue;
    if (!shown) {
      std::ostringstream o;
      o << "expected " << alarm_list(c.codes) << " on " << axis_letters(c.axes) << "; seen:";
      for (std::size_t a = 0; a < kAxisCount; ++a)
        if (w.axis_alarms[a]) o << " " << letter(a) << " " << alarm_list(w.axis_alarms[a]) << ";";
      if (w.global_alarms) o << " global " << alarm_list(w.global_alarms);
      return Unexplained{(c.kind.empty() ? c.what : c.kind) + " raised no alarm of its own", c.what + ": " + o.str()};
    }
    if (c.phase_axis) {
      const std::size_t a = *c.phase_axis;
      const Alarm& first = w.first_alarm[a];
      // The first alarm may be an earlier cause's on the same axis (a second
      // drive fault on an axis stopped by its first while the failure policy
      // lets the others finish: seed 7314363).
      const bool earlier = std::any_of(causes.list.begin(), causes.list.end(), [&](const Cause& d) {
        return d.phase_axis == a && (d.codes & alarm_bit(first.code)) &&
               (first.phase == d.phase || first.phase == d.phase_seen);
      });
      if ((c.codes & alarm_bit(first.code)) && first.phase != c.phase && first.phase != c.phase_seen && !earlier) {
        std::ostringstream o;
        o << c.what << " struck in phase " << phase_name(c.phase) << " (" << phase_name(c.phase_seen)
          << " when the engine read it), its alarm says phase " << phase_name(first.phase);
        return Unexplained{"an alarm names another phase than the one its cause struck in", o.str()};
      }
    }
  }
  return std::nullopt;
}

double path_bound(rig::Rig& r, const Machine& m, std::size_t a, double x_start) {
  const AxisSettings e = effective(r.settings, a);
  const double seek_v = mm_per_min_to_mm_per_s(e.seek_feedrate_mm_per_min);
  const double latch_v = mm_per_min_to_mm_per_s(e.latch_feedrate_mm_per_min);
  const double acc = e.acceleration_mm_per_s2;
  const double stop = acc > 0 ? stop_distance_mm(seek_v, acc) + seek_v * m.max_dt_s : 0;
  double final_d = 0;
  if (final_move_wanted(e)) {
    final_d = std::abs(e.final_position_mm - e.home_position_mm);
    if (mode_is_absolute(e.mode)) {
      const auto& c = r.sim().axis_config(a);
      final_d = std::abs(e.final_position_mm - (x_start + c.absolute_offset_mm - e.home_position_mm));
    }
  }
  if (e.mode == HomingMode::hard_stop)
    return e.pre_move_distance_mm + e.max_seek_travel_mm + stop_distance_mm(latch_v, acc) + latch_v * m.max_dt_s +
           e.pull_off_mm + final_d + stop + 1;
  if (e.mode == HomingMode::drive) {
    // The drive's own travel to its home (from where the cycle started), then the final move.
    const auto& c = r.sim().axis_config(a);
    return std::abs(c.drive_home_position_mm - x_start) + final_d + stop + 1e-6;
  }
  if (!mode_uses_switch(e.mode)) return final_d + stop + 1e-6;
  const double over = e.max_stop_distance_mm + seek_v * m.max_dt_s + 1e-3;
  if (e.mode == HomingMode::home_cam) {
    // The search out to the limit switch ahead and its braking, the whole
    // search back, the stop on the cam, the latch across it, the pull-off.
    const double latch_stop = stop_distance_mm(latch_v, acc) + latch_v * m.max_dt_s;
    return 2 * (e.max_seek_travel_mm + stop) + over + e.max_backoff_mm + latch_stop + e.pull_off_mm + final_d + stop + 1;
  }
  const double index = e.mode == HomingMode::switch_index ? e.index_pitch_mm * 1.1 + stop_distance_mm(latch_v, acc) : 0;
  double b = e.pre_move_distance_mm + e.max_seek_travel_mm + over + (mode_is_pushing(e.mode) ? e.push_distance_mm : 0) +
             2 * e.max_backoff_mm + index + e.pull_off_mm + std::abs(e.switch_compensation_mm) + final_d + stop + 1;
  const int partner = partner_index(r.settings, a);
  if (partner >= 0) {
    const int slave = master_index(r.settings, a) >= 0 ? static_cast<int>(a) : partner;
    const AxisSettings& sl = r.settings.axes[static_cast<std::size_t>(slave)];
    b += sl.max_misalignment_mm + std::abs(sl.pull_off_mm - r.settings.axes[static_cast<std::size_t>(master_index(r.settings, static_cast<std::size_t>(slave)))].pull_off_mm);
    // A commutator slave rides along with its master, then searches its own edge.
    if (slave == static_cast<int>(a) && sl.slave_mode == SlaveMode::external_commutator)
      b += e.pull_off_mm + sl.max_misalignment_mm + e.max_stop_distance_mm + 2 * e.max_backoff_mm + e.pull_off_mm + 1;
  }
  return b;
}

double time_bound(rig::Rig& r, const Machine& m, const CyclePlan& plan) {
  double t = 20;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(plan.movers & axis_bit(a))) continue;
    const AxisSettings e = effective(r.settings, a);
    const double v = mm_per_min_to_mm_per_s(searches(e.mode) ? e.latch_feedrate_mm_per_min : e.seek_feedrate_mm_per_min);
    if (v > 0) t += 2 * path_bound(r, m, a, r.actual(a)) / v;
    if (e.mode == HomingMode::drive) t += e.drive_home_timeout_s;  // at most, whatever the drive does
    // The way back of return_to_start, one step after the other.
    if (r.settings.global.failure_policy == FailurePolicy::return_to_start && return_speed(e) > 0)
      t += 2 * path_bound(r, m, a, r.actual(a)) / return_speed(e);
  }
  return t;
}

// What the failure policy let go on ended as it says, unless another
// failure (or an abort) stopped it: under finish_independent each axis still
// homing at the first alarm ends homed; under return_to_start each axis the
// rule sends back ends where the cycle found it, no longer homed (the way
// back undoes the cycle).
namespace {
void policy_verdict(Watch& w, rig::Rig& r) {
  if (w.later_failure) return;
  const Status& st = r.status();
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisMask bit = axis_bit(a);
    if (w.wind_down == FailurePolicy::finish_independent && (w.finishers & bit) && !st.axes[a].homed)
      w.fail("an axis the failure policy let finish its homing did not end homed",
             letter(a) + " in phase " + std::string(phase_name(st.axes[a].phase)) + "; first alarms " +
                 alarm_list(w.alarms_seen));
    if (w.wind_down != FailurePolicy::return_to_start || !(w.returners & bit)) continue;
    const double x = r.actual(a);
    if (std::abs(x - w.window_start_x[a]) > w.back_tolerance(a) && !w.stop_touched(a)) {
      std::ostringstream o;
      o << letter(a) << " carriage " << x << ", the cycle found it at " << w.window_start_x[a] << " (tolerance "
        << w.back_tolerance(a) << "); alarms " << alarm_list(w.alarms_seen);
      w.fail("an axis the failure policy sends back did not end where the cycle found it", o.str());
    }
    if (st.axes[a].homed) w.fail("an axis the failure policy sent back is still homed", letter(a));
  }
}
}  // namespace

void verdict(Watch& w, rig::Rig& r, const Machine& m, const Causes& causes, std::uint32_t cycles_before) {
  const CyclePlan& plan = w.plan;
  const Status& st = r.status();
  const AlarmBits seen = w.alarms_seen;
  if (auto u = explain(w, causes, r.settings)) w.fail(u->what, u->detail);
  if (w.refused) {
    const AlarmBits settings_codes = code_bits({AlarmCode::settings_fault, AlarmCode::slave_sensor_missing});
    if (!(seen & settings_codes)) w.fail("a cycle the configuration check refuses ended without a settings alarm", alarm_list(seen));
    if (st.last_command_result != CommandResult::refused_settings_fault)
      w.fail("a cycle the configuration check refuses was not refused", std::string(command_result_name(st.last_command_result)));
  }
  // The way back of return_to_start is at most the way out.
  const double ways = r.settings.global.failure_policy == FailurePolicy::return_to_start ? 2 : 1;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const double bound = ways * path_bound(r, m, a, w.window_start_x[a]) + w.extra_path[a];
    if (w.path[a] > bound) {
      std::ostringstream o;
      o << kAxisUpper[a] << " travelled " << w.path[a] << ", bound " << bound;
      w.fail("a cycle travelled beyond its bounded distance", o.str());
    }
  }
  policy_verdict(w, r);
  if (seen != 0 || w.refused) return;
  if (st.homing_cycles != cycles_before + 1) {
    if (causes.aborted_quietly) return;
    w.fail("a cycle ended without an alarm but was not counted as completed");
  }
  if (plan.all) w.assign_unsequenced();
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisMask bit = axis_bit(a);
    if (!((plan.covered | plan.unsequenced) & bit)) continue;
    const AxisSettings e = effective(r.settings, a);
    if (e.mode == HomingMode::disabled && master_index(r.settings, a) < 0) continue;
    // A measurement that pushed into a hard stop lost its steps there: unhomed (service_acts.cpp judges it).
    if (!st.axes[a].homed && (w.measured & bit) && e.mode == HomingMode::hard_stop) continue;
    if (!st.axes[a].homed) {
      w.fail("a cycle ended without an alarm and an axis of it not homed", std::string(1, kAxisUpper[a]));
      continue;
    }
    if (!(w.flipped & bit) && (plan.covered & bit))
      w.fail("an axis was homed without ever being unhomed by its cycle", std::string(1, kAxisUpper[a]));
    if ((w.reversal_known & bit) && !(w.tampered & bit) && ((w.reversed ^ w.reversal_expected) & bit)) {
      std::ostringstream o;
      o << kAxisUpper[a] << " started the cycle at " << w.window_start_x[a];
      w.fail((w.reversed & bit) ? "the home cam search reversed although its cam lay ahead"
                                : "the home cam search did not reverse although its cam lay behind",
             o.str());
    }
    const Truth& t = w.truth[a];
    if (!t.valid || (w.measured & bit)) continue;  // a measured axis ends at its far end
    const double x = r.actual(a);
    const bool final_move = (plan.covered & bit) && final_move_wanted(e);
    if (final_move) {
      if (std::abs(st.axes[a].position_mm - e.final_position_mm) > 1e-9) {
        std::ostringstream o;
        o << kAxisUpper[a] << " at " << st.axes[a].position_mm << ", final position " << e.final_position_mm;
        w.fail("the final move did not end at the final position", o.str());
      }
    } else if (t.has_rest && std::abs(x - t.rest) > t.tol) {
      std::ostringstream o;
      o << kAxisUpper[a] << " carriage " << x << ", rest point " << t.rest << " (tolerance " << t.tol << ")";
      w.fail("did not come to rest at pull-off from its reference edge", o.str());
    }
  }
}

}  // namespace campaign
