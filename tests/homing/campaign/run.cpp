#include "run.hpp"

#include "../truth.hpp"
#include "homing/motion.hpp"

namespace campaign {

Run::Run(std::uint64_t seed)
    : m_(generate(seed)),
      d_(seed, 2),
      periods_(seed, 3),
      indexer_events_(seed, 8),
      limit_acts_(seed, 15),
      measure_acts_(seed, 18),
      restarts_(seed, 19) {
  r_.settings = m_.settings;
  r_.machine = m_.sim;
  const double max_dt = m_.max_dt_s;
  // Late periods: most about 1 ms, one in ten late by up to max_dt.
  r_.next_dt = [this, max_dt] { return periods_.chance(0.1) ? periods_.u(0.001, max_dt) : periods_.u(0.0005, 0.0015); };
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (m_.plan[a].encoder_invalid) encoder_invalid_ |= axis_bit(a);
  r_.tweak_inputs = [this](Inputs& in) {
    in.communication_lost = comm_lost_;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (encoder_invalid_ & axis_bit(a)) in.axes[a].absolute_valid = false;
  };
  r_.sim().set_homing_permit(true);
  w_ = std::make_unique<Watch>(r_, m_);
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const sim::Fault f = m_.plan[a].start_fault;
    if (f == sim::Fault::sensor_stuck_inactive || (f == sim::Fault::wire_break && !r_.settings.axes[a].sensor_nc))
      w_->dead_sensor |= axis_bit(a);
  }
  r_.on_period = [this](rig::Rig&) { w_->period(); };
}

void Run::say(const std::string& what) { log_ << "  t " << r_.sim().time_s() << ": " << what << "\n"; }

void Run::settle(double max_s) {
  // At rest: no carriage moving, and no locking indexer still unlocking or locking.
  r_.run_until([&] { return (!r_.any_moving() && [&] {
                              for (std::size_t a = 0; a < kAxisCount; ++a)
                                if (r_.sim().moving(a) || r_.axis(a).phase == Phase::unlock ||
                                    r_.axis(a).phase == Phase::lock)
                                  return false;
                              return true;
                            }()) || !ok(); }, max_s);
}

bool Run::homed_axis(std::size_t a) const { return w_->truth[a].valid && r_.status().axes[a].homed; }

void Run::power_up() {
  if (m_.start_held_at_powerup) {
    say("power-up with the start button held");
    r_.sim().set_start_button(true);
  }
  w_->powering_up = true;
  for (int i = 0; i < m_.powerup_periods && ok(); ++i) step();
  r_.sim().set_start_button(false);
  step();
  w_->powering_up = false;
  // An engine that (wrongly) judged a command at power-up: put the machine back.
  if (w_->powerup_started && ok()) {
    r_.pending.abort = true;
    step();
    settle(10);
    r_.reset_alarm();
    settle(10);
    put_back(kAllAxes);
    w_->powerup_started = false;
  }
}

std::vector<Event> Run::random_events(const CyclePlan& plan, double estimate) {
  std::vector<Event> out = common_events(plan, estimate);
  add_indexer_event(out, plan, estimate);
  return out;
}

std::vector<Event> Run::common_events(const CyclePlan& plan, double estimate) {
  std::vector<Event> out;
  if (!d_.chance(0.5)) return out;
  Event e;
  e.kind = static_cast<EventKind>(d_.integer(0, kCommonEventKinds - 1));
  e.at_s = d_.u(0, estimate);
  std::vector<std::size_t> movers;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (plan.movers & axis_bit(a)) movers.push_back(a);
  if (movers.empty()) return out;
  e.axis = movers[static_cast<std::size_t>(d_.integer(0, static_cast<int>(movers.size()) - 1))];
  const bool sensor = e.kind == EventKind::stuck_active || e.kind == EventKind::stuck_inactive || e.kind == EventKind::wire_break;
  if (sensor && !mode_uses_switch(effective(r_.settings, e.axis).mode)) return out;
  if (e.kind == EventKind::permit_off && !r_.settings.global.permit_required) return out;
  if (e.kind == EventKind::drive_done_lost && effective(r_.settings, e.axis).mode != HomingMode::drive) return out;
  // Half of them aimed at a phase the axis runs (a slave's pair phases too).
  const std::vector<Phase> phases = phases_run(e.axis);
  if (!phases.empty() && d_.chance(0.5)) {
    e.aimed = true;
    e.phase = phases[static_cast<std::size_t>(d_.integer(0, static_cast<int>(phases.size()) - 1))];
    e.after_periods = d_.chance(0.5) ? 0 : d_.integer(1, 20);
  }
  out.push_back(e);
  return out;
}

// A locking indexer's fault during a later cycle, on an axis it moves.
void Run::add_indexer_event(std::vector<Event>& events, const CyclePlan& plan, double estimate) {
  std::vector<std::size_t> fitted;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (m_.plan[a].indexer && (plan.movers & axis_bit(a))) fitted.push_back(a);
  if (fitted.empty() || !indexer_events_.chance(0.3)) return;
  Event e;
  e.kind = indexer_events_.pick({EventKind::indexer_stuck_locked, EventKind::indexer_never_locks});
  e.axis = fitted[static_cast<std::size_t>(indexer_events_.integer(0, static_cast<int>(fitted.size()) - 1))];
  e.at_s = indexer_events_.u(0, estimate);
  events.push_back(e);
}

// The phases an axis runs in a cycle, as README describes its mode (a
// commutator slave also aligns; every gantry side may wait for the other).
std::vector<Phase> Run::phases_run(std::size_t a) const {
  const AxisSettings e = effective(r_.settings, a);
  std::vector<Phase> p;
  if (e.mode == HomingMode::home_cam) {
    p = {Phase::cam_seek, Phase::limit_reversal, Phase::cam_stop, Phase::cam_latch, Phase::pull_off};
  } else if (mode_uses_switch(e.mode)) {
    p = {Phase::seek, Phase::stop, Phase::back_off, Phase::pull_off};
    if (e.pre_move_mode != PreMove::none) p.push_back(Phase::pre_move);
    if (mode_reapproaches(e.mode)) p.push_back(Phase::reapproach);
    if (e.mode == HomingMode::switch_index) p.push_back(Phase::index);
    if (mode_is_pushing(e.mode)) p.push_back(Phase::push);
    if (partner_index(r_.settings, a) >= 0) p.push_back(Phase::waiting);
    if (pair_master(r_.settings, a) >= 0 && r_.settings.axes[a].slave_mode == SlaveMode::external_commutator)
      p.push_back(Phase::align_slave);
  }
  if (e.mode == HomingMode::hard_stop) {
    p = {Phase::push_to_stop, Phase::pull_off};
    if (e.pre_move_mode != PreMove::none) p.push_back(Phase::pre_move);
  }
  // A software-slaved pair on its sensors first clears them together.
  if (const int partner = partner_index(r_.settings, a); partner >= 0) {
    const std::size_t slave = master_index(r_.settings, a) >= 0 ? a : static_cast<std::size_t>(partner);
    if (r_.settings.axes[slave].slave_mode == SlaveMode::own_output) p.push_back(Phase::clear_sensors);
  }
  if (e.mode == HomingMode::drive) p.push_back(Phase::drive_homing);
  if (final_move_wanted(e)) p.push_back(Phase::final_move);
  return p;
}

void Run::apply_in_motion(const Event& e, Causes& causes) {
  const std::size_t from = causes.list.size();
  apply(e, causes, CyclePlan{});
  step();
  for (std::size_t i = from; i < causes.list.size(); ++i)
    if (causes.list[i].phase_axis) causes.list[i].phase_seen = r_.axis(*causes.list[i].phase_axis).phase;
}

void Run::apply(const Event& e, Causes& causes, const CyclePlan& plan) {
  say(std::string(event_name(e.kind)) + " on " + kAxisUpper[e.axis]);
  if (e.kind != EventKind::abort && e.kind != EventKind::reset && e.kind != EventKind::home_again) w_->event_applied();
  // The simulated axis has one fault at a time: a new one replaces the old.
  // A locking indexer's fault replaced by another need not show any more;
  // an indexer fault does not replace another (the campaign keeps that one).
  const sim::Fault present = r_.sim().axis_config(e.axis).fault;
  const bool indexer_event = e.kind == EventKind::indexer_stuck_locked || e.kind == EventKind::indexer_never_locks;
  if (indexer_event && present != sim::Fault::none) {
    say(std::string("(not applied: ") + kAxisUpper[e.axis] + " has another fault)");
    return;
  }
  auto set_fault = [&](sim::Fault f) {
    auto c = r_.sim().axis_config(e.axis);
    c.fault = f;
    r_.sim().set_axis_config(e.axis, c);
    if (present == sim::Fault::indexer_stuck_locked || present == sim::Fault::indexer_never_locks) {
      const AlarmBits indexer_codes =
          code_bits({AlarmCode::unlock_not_confirmed, AlarmCode::lock_not_confirmed, AlarmCode::lock_engaged});
      for (Cause& k : causes.list)
        if ((k.axes & axis_bit(e.axis)) && (k.codes & indexer_codes) && k.must) {
          k.must = false;
          k.what += " (its fault replaced by another: it need not show)";
        }
    }
  };
  switch (e.kind) {
    case EventKind::abort:
      r_.pending.abort = true;
      w_->abort_applied();
      break;
    case EventKind::estop: r_.sim().set_estop(true); break;
    case EventKind::drive_fault:
      set_fault(sim::Fault::drive_fault);
      w_->carriage_jumped(e.axis);  // the motor runs on without the carriage
      if (!w_->in_window) w_->pair_slipped(e.axis);
      break;
    case EventKind::stuck_active:
      set_fault(sim::Fault::sensor_stuck_active);
      w_->tampered |= axis_bit(e.axis);
      w_->stuck_on |= axis_bit(e.axis);
      break;
    case EventKind::stuck_inactive:
      set_fault(sim::Fault::sensor_stuck_inactive);
      w_->tampered |= axis_bit(e.axis);
      w_->dead_sensor |= axis_bit(e.axis);
      break;
    case EventKind::wire_break:
      set_fault(sim::Fault::wire_break);
      w_->tampered |= axis_bit(e.axis);
      if (!r_.settings.axes[e.axis].sensor_nc) w_->dead_sensor |= axis_bit(e.axis);
      else w_->stuck_on |= axis_bit(e.axis);
      break;
    case EventKind::comm_lost: comm_lost_ = true; break;
    case EventKind::permit_off: r_.sim().set_homing_permit(false); break;
    case EventKind::reset: r_.pending.reset_alarm = true; break;
    case EventKind::home_again: r_.pending.home_all = true; break;
    case EventKind::drive_done_lost: set_fault(sim::Fault::drive_done_lost); break;
    case EventKind::indexer_stuck_locked:
    case EventKind::indexer_never_locks: {
      const bool unlocked = r_.engine.outputs().axes[e.axis].indexer_unlock;
      indexer_cause(causes, e, r_.settings, r_.status(), plan, unlocked, r_.sim().indexer_locked(e.axis),
                    r_.sim().moving(e.axis));
      if (e.kind == EventKind::indexer_stuck_locked) {
        set_fault(sim::Fault::indexer_stuck_locked);
        // Struck under an axis unlocked for motion: its motor may brake
        // against the pin (steps lost), the one motion the watch excuses.
        if (unlocked) {
          w_->lock_struck |= axis_bit(e.axis);
          w_->carriage_jumped(e.axis);
        }
      } else {
        set_fault(sim::Fault::indexer_never_locks);
      }
      break;
    }
    case EventKind::count: break;
  }
  event_cause(causes, e, r_.settings, r_.status(), plan);
  if (e.kind == EventKind::stuck_active || e.kind == EventKind::stuck_inactive || e.kind == EventKind::wire_break)
    for (Cause& c : causes.list)
      if (c.needs_true_sensor && c.must && (c.axes & axis_bit(e.axis))) {
        c.must = false;
        c.what += " (its sensor lies since: it need not show)";
      }
  // What no engine can see, named: a slave's sensor blinded (stuck inactive,
  // an open NO circuit) while the slave searches off it looks exactly like
  // its release edge, so the engine squares there, short of a skew it can no
  // longer see; and a sensor stuck active that goes dead during the back-off
  // is, to the engine, its release edge. Those causes may still show, but
  // need not.
  if (w_->dead_sensor & axis_bit(e.axis)) {
    const std::string axis(1, kAxisUpper[e.axis]);
    for (Cause& c : causes.list)
      if ((master_index(r_.settings, e.axis) >= 0 && c.what == axis + "'s skew beyond its max misalignment") ||
          c.what == axis + "'s faulty sensor") {
        c.must = false;
        c.what += " (its sensor went dead: it need not show)";
      }
  }
}

// One homing cycle, to its end and the machine at rest, then its verdict.
bool Run::cycle(bool all, AxisMask mask, std::vector<Event> events, bool by_button, AxisMask measure) {
  const CyclePlan plan = plan_cycle(r_.settings, all, mask);
  const bool refused = first_fault(r_.settings).has_value();
  std::array<std::optional<double>, kAxisCount> rack{};
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (m_.plan[a].role == Role::slave) rack[a] = w_->pair_rack(a);
  Causes causes = standing_causes(r_, m_, plan, refused, encoder_invalid_, rack);
  const std::uint32_t cycles_before = r_.status().homing_cycles;
  cam_on_start_ = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (r_.sim().sensor_active(a)) cam_on_start_ |= axis_bit(a);
  w_->begin_window(plan, refused);
  w_->clear_alarms_seen();
  // A measurement travels on from the rest point: to the far end within
  // max_seek_travel, off a limit switch within max_backoff, or pull-off off a stop.
  double measure_s = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(measure & axis_bit(a))) continue;
    const AxisSettings& s = r_.settings.axes[a];
    const double latch_v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
    w_->measured |= axis_bit(a);
    w_->extra_path[a] = s.max_seek_travel_mm + s.max_backoff_mm + s.pull_off_mm + 1;
    measure_s = 1.2 * (s.max_seek_travel_mm + s.max_backoff_mm + s.pull_off_mm) / latch_v + 5;
  }
  {
    std::ostringstream o;
    o << (all ? "home all" : "home axes ");
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (!all && (mask & axis_bit(a))) o << kAxisUpper[a];
    o << (by_button ? " by the start button" : " by command") << (refused ? " (the check refuses it)" : "");
    if (measure) o << ", a measurement of its travel";
    say(o.str());
  }
  int button_periods = 0;
  if (by_button) {
    r_.sim().set_start_button(true);
    button_periods = d_.integer(1, 30);
  } else if (measure) {
    r_.pending.measure_axes = measure;
  } else if (all) {
    r_.pending.home_all = true;
  } else {
    r_.pending.home_axes = mask;
  }
  const double t0 = r_.sim().time_s();
  step();
  const CommandResult res = r_.status().last_command_result;
  if (refused) {
    if (r_.status().homing) w_->fail("a cycle the configuration check refuses started");
  } else if (res != CommandResult::accepted || !r_.status().homing) {
    // Nothing started it: a cycle that ended in its first period (every axis
    // without motion) is the only excuse.
    if (res != CommandResult::accepted)
      w_->fail("a home command was not accepted", std::string(command_result_name(res)));
  }
  const double limit = time_bound(r_, m_, plan) + measure_s;
  AxisMask final_seen = 0;
  std::vector<bool> done(events.size(), false);
  std::vector<int> in_phase(events.size(), 0);
  while (r_.status().homing && r_.sim().time_s() - t0 < limit && ok()) {
    bool comm_lost_now = false;
    const bool cycle_clean = !r_.status().alarm;
    const std::size_t applied_from = causes.list.size();
    for (std::size_t i = 0; i < events.size(); ++i) {
      const Event& ev = events[i];
      if (done[i]) continue;
      // Aimed: counted from the first period the axis is seen in its phase.
      if (ev.aimed && (in_phase[i] > 0 || r_.axis(ev.axis).phase == ev.phase)) ++in_phase[i];
      const bool due = ev.aimed ? in_phase[i] > ev.after_periods : r_.sim().time_s() - t0 >= ev.at_s;
      if (!due) continue;
      done[i] = true;
      if (ev.aimed) {
        say(std::string("aimed at ") + kAxisUpper[ev.axis] + "'s " + std::string(phase_name(ev.phase)) + " + " +
            std::to_string(ev.after_periods) + " periods:");
        mark("event aimed at phase " + std::string(phase_name(ev.phase)), seen::present);
      }
      apply(ev, causes, plan);
      comm_lost_now = comm_lost_now || ev.kind == EventKind::comm_lost;
      acts_ |= act::event_in_cycle;
    }
    if (button_periods > 0 && --button_periods == 0) r_.sim().set_start_button(false);
    const bool home_again = r_.pending.home_all;
    step();
    final_move_into_limit(causes, final_seen);
    measure_period(causes);
    // An input the simulator changed is read by the engine in the next
    // period: the phase it then runs is the one its alarm may carry too.
    for (std::size_t i = applied_from; i < causes.list.size(); ++i)
      if (causes.list[i].phase_axis) causes.list[i].phase_seen = r_.axis(*causes.list[i].phase_axis).phase;
    // The last carriage arrived at rest in the very period the link was lost
    // and a failed cycle's way back ended: nothing moved after the engine saw
    // it, so nothing to stop. A cycle free of alarms stops with it anyway.
    if (comm_lost_now && !cycle_clean && !r_.status().homing && !r_.any_moving())
      for (Cause& c : causes.list)
        if (c.what == "the communication loss") c.must = false;
    if (home_again) {
      const CommandResult again = r_.status().last_command_result;
      if (r_.status().homing && again != CommandResult::already_running && again != CommandResult::refused_busy)
        w_->fail("a second home command during a cycle was not refused", std::string(command_result_name(again)));
    }
  }
  r_.sim().set_start_button(false);
  if (r_.status().homing && ok()) w_->fail("a cycle did not end within its time bound");
  settle(10);
  last_cycle_s_ = r_.sim().time_s() - t0;
  w_->end_window();
  {
    std::ostringstream o;
    o << "cycle ended " << state_name(r_.status().state) << ", alarms " << alarm_list(w_->alarms_seen);
    say(o.str());
  }
  // A carriage braking after the cycle stopped (another axis's alarm, an
  // abort, an e-stop) may run onto the limit switch its search was heading
  // for: a trip outside homing, of that axis alone (campaign seed 571), in
  // phase idle when it came to rest on the switch (seed 119).
  // Under return_to_start the braking is the first part of the way back, still
  // in the cycle: limit_in_homing in phase return_to_start (seed 7201552).
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const Alarm& first = w_->first_alarm[a];
    if (!r_.settings.axes[a].limits_fitted) continue;
    if (first.code == AlarmCode::limit_switch && (first.phase == Phase::stopping || first.phase == Phase::idle))
      causes.add(std::string(1, kAxisUpper[a]) + "'s limit switch met braking after the cycle stopped",
                 {AlarmCode::limit_switch}, axis_bit(a));
    if (first.code == AlarmCode::limit_in_homing && first.phase == Phase::return_to_start)
      causes.add(std::string(1, kAxisUpper[a]) + "'s limit switch met braking for the way back",
                 {AlarmCode::limit_in_homing}, axis_bit(a));
  }
  if (ok()) verdict(*w_, r_, m_, causes, cycles_before);
  mark_cycle(plan, causes, ok() && w_->alarms_seen == 0 && !refused);
  if (r_.status().state == MachineState::homed && w_->alarms_seen == 0 && ok()) {
    ever_homed_ = true;
    acts_ |= act::homed;
    if (by_button) acts_ |= act::start_button_cycle;
    if (++homed_cycles_ > 1) acts_ |= act::rehomed;
    if (alarm_seen_) acts_ |= act::alarm_then_homed;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (m_.plan[a].role == Role::slave && (plan.covered & axis_bit(a)))
        acts_ |= m_.plan[a].commutator ? act::homed_commutator_gantry : act::homed_software_gantry;
  }
  if (w_->alarms_seen) alarm_seen_ = true;
  w_->tampered = 0;
  return ok() && !r_.status().alarm && w_->alarms_seen == 0;
}

// A final move whose target lies past a limit switch must stop there with
// limit_in_homing (the target as the truth places it, once the axis is homed).
void Run::final_move_into_limit(Causes& causes, AxisMask& seen_final) {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisMask bit = axis_bit(a);
    if ((seen_final & bit) || r_.axis(a).phase != Phase::final_move) continue;
    seen_final |= bit;
    const AxisSettings e = effective(r_.settings, a);
    const sim::Fault f = r_.sim().axis_config(a).fault;
    if (!e.limits_fitted || !w_->truth[a].valid || f == sim::Fault::limits_dead || f == sim::Fault::limits_stuck) continue;
    const auto& c = r_.sim().axis_config(a);
    const double target = e.final_position_mm - w_->truth[a].offset;
    // Within 10 um of the switch either outcome is right: the carriage may
    // come to rest a hair past it (seed 6617474: 1 um) or just short.
    const double past = std::max(target - c.limit_max_mm, c.limit_min_mm - target);
    if (past > -0.01)
      causes.add(std::string(1, kAxisUpper[a]) + "'s final position beyond its limit switch", {AlarmCode::limit_in_homing},
                 bit, past > 0.01);
  }
}

namespace {

std::string gantry_key(const Settings& s, std::size_t slave) {
  return s.axes[slave].slave_mode == SlaveMode::external_commutator ? "gantry external commutator" : "gantry software-slaved";
}

}  // namespace

// Every mode and gantry the machine has, as generated.
void Run::mark_machine() {
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (m_.plan[a].role == Role::slave) {
      const std::size_t mi = static_cast<std::size_t>(m_.plan[a].partner);
      const std::string k = gantry_key(m_.settings, a);
      mark(k, seen::present);
      mark(k + ", master " + std::string(mode_name(m_.settings.axes[mi].mode)), seen::present);
    } else if (m_.settings.axes[a].mode != HomingMode::disabled) {
      mark("mode " + std::string(mode_name(m_.settings.axes[a].mode)), seen::present);
    }
    if (m_.plan[a].limits) mark("limit switches fitted", seen::present);
    if (m_.plan[a].following_error) mark("hard_stop by following error", seen::present);
    if (m_.plan[a].reach_side) mark("a limit switch within jogs, moves or the final move", seen::present);
    if (m_.settings.axes[a].mode == HomingMode::home_cam) {
      for (const std::string& k : home_cam_keys(a)) mark(k, seen::present);
      mark(std::string("home_cam starting ") + start_key(m_.plan[a].cam_start), seen::present);
    }
  }
  mark("failure policy " + std::string(name_of(m_.settings.global.failure_policy)), seen::present);
}

const char* Run::start_key(CamStart c) {
  return c == CamStart::on_cam ? "on the cam" : c == CamStart::behind ? "with the cam behind" : "with the cam ahead";
}

// A home_cam axis's coverage rows besides its mode: its cam edge and its switches' wiring.
std::vector<std::string> Run::home_cam_keys(std::size_t a) const {
  const AxisSettings& s = r_.settings.axes[a];
  std::vector<std::string> k{std::string("home_cam cam_edge ") + (s.cam_edge == CamEdge::ahead ? "ahead" : "behind")};
  if (s.limits_nc) k.push_back("home_cam limit switches NC");
  return k;
}

// What a cycle reached: each cause present, and whether its own alarm showed;
// each covered mode and gantry homed (a clean cycle) or alarmed.
void Run::mark_cycle(const CyclePlan& plan, const Causes& causes, bool clean) {
  // A failure policy at work: axes that went on homing, or back, after a failure.
  const std::string policy = "failure policy " + std::string(name_of(w_->wind_down));
  if (w_->finishers) mark(policy + ": axes finished after a failure", seen::present);
  if (w_->returners) mark(policy + ": axes went back after a failure", seen::present);
  if (w_->wind_down != FailurePolicy::stop_all) mark(policy, seen::alarmed);
  for (const Cause& c : causes.list) {
    bool shown = (w_->global_alarms & c.global) != 0;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if ((c.axes & axis_bit(a)) && (w_->axis_alarms[a] & c.codes)) shown = true;
    mark("cause " + (c.kind.empty() ? c.what : c.kind), static_cast<std::uint8_t>(seen::present | (shown ? seen::alarmed : 0)));
  }
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!(plan.covered & axis_bit(a))) continue;
    const std::uint8_t bits = static_cast<std::uint8_t>((clean && r_.status().axes[a].homed ? seen::homed : 0) |
                                                        (w_->axis_alarms[a] ? seen::alarmed : 0));
    if (!bits) continue;
    if (m_.plan[a].role == Role::slave) {
      const std::size_t mi = static_cast<std::size_t>(m_.plan[a].partner);
      const std::string k = gantry_key(m_.settings, a);
      const std::uint8_t pair = static_cast<std::uint8_t>(bits | (w_->axis_alarms[mi] ? seen::alarmed : 0));
      mark(k, pair);
      mark(k + ", master " + std::string(mode_name(m_.settings.axes[mi].mode)), pair);
      if (!m_.plan[a].bad_skew && std::abs(w_->rack_at_window_start(a)) > 0.5 * m_.settings.axes[a].max_misalignment_mm)
        mark("gantry starting racked by an earlier stop", static_cast<std::uint8_t>(pair | seen::present));
    } else if (m_.settings.axes[a].mode != HomingMode::disabled) {
      mark("mode " + std::string(mode_name(m_.settings.axes[a].mode)), bits);
    }
    if (m_.plan[a].limits) mark("limit switches fitted", bits);
    if (m_.plan[a].following_error) mark("hard_stop by following error", bits);
    if (r_.settings.axes[a].mode == HomingMode::home_cam) {
      for (const std::string& k : home_cam_keys(a)) mark(k, bits);
      if (w_->reversal_known & axis_bit(a))
        mark(std::string("home_cam starting ") +
                 start_key((cam_on_start_ & axis_bit(a))         ? CamStart::on_cam
                           : (w_->reversal_expected & axis_bit(a)) ? CamStart::behind
                                                                   : CamStart::ahead),
             bits);
    }
  }
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (w_->reversed & axis_bit(a)) mark("home_cam reversed at a limit switch", seen::present);
}

// Clear every cause, then reset: the reset must be taken.
// The technician pushes carriages back where they started (a sensor fault
// may have let a seek run past its cam); a gantry's both sides together.
void Run::put_back(AxisMask mask) {
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if (mask & axis_bit(a)) {
      const int p = partner_index(r_.settings, a);
      if (p >= 0) mask |= axis_bit(static_cast<std::size_t>(p));
    }
  bool any = false;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((mask & axis_bit(a)) && r_.actual(a) != m_.sim.axes[a].actual_position_mm)
      any = r_.sim().place(a, m_.sim.axes[a].actual_position_mm) || any;
  if (!any) return;
  say("carriages put back by hand: " + std::to_string(mask));
  w_->carriages_placed();
  // The inputs (the encoders) show the new places after a period.
  for (int i = 0; i < 3; ++i) step();
  // A gantry moved by hand: the technician unhomes it, as the alarm's text
  // says, so the module forgets where it was square (docs/homing-methods.md
  // "Gantries: racking").
  AxisMask pairs = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a)
    if ((mask & axis_bit(a)) && partner_index(r_.settings, a) >= 0) pairs |= axis_bit(a);
  if (!pairs) return;
  say("unhome the gantry moved by hand: " + std::to_string(pairs));
  r_.pending.unhome_axes |= pairs;
  step();
  w_->pair_unhomed(pairs);
}

void Run::recover() {
  say("recover: e-stop released, faults cleared, permit on, reset");
  r_.sim().set_estop(false);
  r_.sim().set_homing_permit(true);
  comm_lost_ = false;
  settle(10);
  AxisMask faulted = 0, sensor_faulted = 0, past_cam = 0;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    auto c = r_.sim().axis_config(a);
    if (c.fault == sim::Fault::sensor_stuck_active || c.fault == sim::Fault::sensor_stuck_inactive ||
        c.fault == sim::Fault::wire_break)
      sensor_faulted |= axis_bit(a);
    if (c.fault != sim::Fault::none) {
      // An indexer's fault leaves the carriage where it was: nothing to put back.
      const bool indexer = c.fault == sim::Fault::indexer_stuck_locked || c.fault == sim::Fault::indexer_never_locks;
      if (c.fault != sim::Fault::drive_fault && !indexer) faulted |= axis_bit(a);
      c.fault = sim::Fault::none;
      r_.sim().set_axis_config(a, c);
    }
  }
  // And those an alarm left past their cam (a short cam, a dead sensor).
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisSettings e = effective(r_.settings, a);
    const auto& c = r_.sim().axis_config(a);
    const double x = r_.actual(a);
    const bool past = dir_of(e) > 0 ? x > c.sensor_max_mm : x < c.sensor_min_mm;
    if (mode_uses_switch(e.mode) && (past || m_.plan[a].short_cam) && !w_->truth[a].valid) {
      faulted |= axis_bit(a);
      past_cam |= axis_bit(a);
    }
  }
  // Half the time a gantry whose sensor failed stays where its alarm left it
  // (the wire mended, the gantry not touched): the next cycle starts racked
  // and must square it back (docs/homing-methods.md "Gantries: racking").
  // Not one left standing on a switch it ran deep into (seed 21086452: its
  // back-off, bounded by max_backoff, could not leave it).
  for (std::size_t s = 0; s < kAxisCount; ++s) {
    if (m_.plan[s].role != Role::slave) continue;
    const std::size_t mi = static_cast<std::size_t>(m_.plan[s].partner);
    const AxisMask pair = static_cast<AxisMask>(axis_bit(s) | axis_bit(mi));
    const bool on_switch = r_.sim().sensor_active(s) || r_.sim().sensor_active(mi);
    if ((sensor_faulted & pair) && !(past_cam & pair) && !on_switch && d_.chance(0.5)) {
      faulted &= static_cast<AxisMask>(~pair);
      say(std::string("gantry ") + kAxisUpper[s] + " left where its alarm stopped it");
    }
  }
  put_back(faulted);
  w_->dead_sensor = 0;
  w_->stuck_on = 0;
  w_->lock_struck = 0;
  if (d_.chance(0.5)) encoder_invalid_ = 0;
  for (int i = 0; i < 3; ++i) step();
  settle(10);
  if (!r_.status().alarm) return;
  r_.reset_alarm();
  if (r_.status().last_command_result != CommandResult::accepted)
    w_->fail("a reset with no cause left was refused", std::string(command_result_name(r_.status().last_command_result)));
  for (int i = 0; i < 3; ++i) step();
  // An alarm's braking may have left a homed shared-limit axis standing on
  // its sensor (no trip is raised while an alarm is latched): once reset, it
  // trips, as it must; a second reset is then taken and only a jog away
  // moves it (seed 7028705).
  if (r_.status().alarm && ok()) {
    bool on_limit = true;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (r_.axis(a).alarm && !(r_.axis(a).alarm.code == AlarmCode::hard_limit && r_.settings.axes[a].shared_limit &&
                                r_.axis(a).sensor))
        on_limit = false;
    if (on_limit) {
      say("a shared-limit axis stands on its sensor: hard limit; reset again");
      r_.reset_alarm();
      for (int i = 0; i < 3; ++i) step();
    }
  }
  if (r_.status().alarm && ok()) {
    std::string codes;
    bool hard = false;
    for (std::size_t a = 0; a < kAxisCount; ++a)
      if (r_.axis(a).alarm) {
        codes += std::string(1, kAxisUpper[a]) + " " + std::string(alarm_name(r_.axis(a).alarm.code)) + "; ";
        hard = hard || r_.axis(a).alarm.code == AlarmCode::hard_limit;
      }
    w_->fail(hard ? "after a hard-limit trip the alarm latched again right after the reset"
                  : "an alarm latched again right after a reset with no cause left",
             codes);
  }
  // Now and then the technician jogs an axis off the limit switch it tripped
  // (only away is allowed, homed or not); else the next cycle starts on it.
  const AlarmBits limit_codes = code_bits({AlarmCode::limit_switch, AlarmCode::limit_in_homing});
  for (std::size_t a = 0; a < kAxisCount && ok() && !r_.status().alarm; ++a) {
    if (!(w_->axis_alarms[a] & limit_codes) || !on_limit_switch(a) || !limit_acts_.chance(0.5)) continue;
    jog_off_limit_switch(a, r_.sim().limit_active(a, true) ? -1 : 1);
  }
}

void Run::follow_ups() {
  const int acts = d_.integer(1, 4);
  for (int i = 0; i < acts && ok(); ++i) {
    if (r_.status().alarm || r_.sim().inputs().estop || comm_lost_ || !r_.sim().inputs().homing_permit) {
      // A watchdog that expired after the motion ended raises nothing but
      // still refuses motion: the link comes back first. So does a permit
      // taken away in the period the cycle ended (seed 7410015997): no
      // alarm, but homing is refused until it is back.
      recover();
      if (ok() && d_.chance(0.6)) {
        const CyclePlan plan = plan_cycle(r_.settings, true, 0);
        cycle(true, 0, random_events(plan, last_cycle_s_), d_.chance(0.2));
      }
      continue;
    }
    limit_switch_trip();
    if (!ok()) break;
    measurement();
    if (!ok()) break;
    restart_with_checks();
    if (!ok()) break;
    if (r_.status().alarm) continue;
    switch (d_.integer(0, 5)) {
      case 5: change_settings(); break;
      case 0: exercise_motion(); break;
      case 1: hard_limit_recovery(); break;
      case 2: lost_steps(); break;
      case 3: {
        // Home some axes again, perhaps with something happening.
        AxisMask mask = 0;
        for (std::size_t a = 0; a < kAxisCount; ++a)
          if (r_.settings.axes[a].mode != HomingMode::disabled && d_.chance(0.4)) mask |= axis_bit(a);
        if (!mask) break;
        const CyclePlan plan = plan_cycle(r_.settings, false, mask);
        cycle(false, mask, random_events(plan, last_cycle_s_), false);
        break;
      }
      default: {
        const CyclePlan plan = plan_cycle(r_.settings, true, 0);
        cycle(true, 0, random_events(plan, last_cycle_s_), d_.chance(0.2));
        break;
      }
    }
  }
}

Outcome Run::run() {
  Outcome out;
  out.seed = m_.seed;
  mark_machine();
  if (auto f = first_fault(r_.settings)) {
    out.refused = true;
    const int p = f->axis < kAxisCount ? partner_index(r_.settings, f->axis) : -1;
    if (m_.invalid == Invalid::none && master_index(r_.settings, f->axis) >= 0 && p >= 0 && inherited_field(f->field))
      w_->fail("the configuration check judges a slave by a setting it inherits from its master",
               describe_fault(*f, r_.settings));
    else if (m_.invalid == Invalid::none) {
      // The generator built it valid by the documented rules: one of the two is wrong.
      out.unexpected_refusal = describe_fault(*f, r_.settings);
      w_->fail("the configuration check refuses a machine the documented rules accept", out.unexpected_refusal);
    }
  } else if (m_.invalid != Invalid::none) {
    w_->fail(std::string("the configuration check accepts a ") + invalid_name(m_.invalid));
  }
  if (ok()) power_up();
  if (ok() && !out.refused && d_.chance(0.3)) motion_before_homing();
  if (ok()) {
    cycle(true, 0, m_.events, m_.start_by_button);
    if (out.refused && ok()) jog_invalid_slave();
  }
  if (ok() && !out.refused) follow_ups();
  out.failed = !ok();
  if (out.failed) out.failure = w_->failure();
  if (out.failed) out.story = story(m_);
  out.log = log_.str();
  out.ever_homed = ever_homed_;
  out.periods = r_.periods;
  out.acts = acts_;
  if (out.refused)
    for (auto& [key, bits] : coverage_)
      if (key.rfind("cause ", 0) != 0) bits |= seen::refused;
  out.coverage = coverage_;
  return out;
}

Outcome run_seed(std::uint64_t seed) { return Run(seed).run(); }

}  // namespace campaign

namespace campaign {

std::string report(const Outcome& o, const char* test_name) {
  std::ostringstream r;
  r << "FAILED: " << o.failure.what << "\n";
  if (!o.failure.detail.empty()) r << "  " << o.failure.detail << "\n";
  r << "replay: HOMING_CAMPAIGN_SEED=" << o.seed << " HOMING_CAMPAIGN_RUNS=1 build/bin/homing_tests \"" << test_name
    << "\"  (HOMING_CAMPAIGN_TRACE=1 prints every phase change); add the seed to replays_test.cpp's list"
    << " and write the bug as a named scenario\nthe machine:\n"
    << o.story << "what happened:\n"
    << o.log;
  return r.str();
}

}  // namespace campaign
