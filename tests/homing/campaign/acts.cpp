// The acts of a run between cycles: jogs and moves, a hard-limit trip and
// its recovery, lost steps, and a jog that must not carry an invalid slave.
#include "../truth.hpp"
#include "run.hpp"

namespace campaign {

void Run::exercise_motion() {
  std::vector<std::size_t> cand;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisSettings e = effective(r_.settings, a);
    // Not one standing on its tripped shared-limit sensor: only a jog away is its to make.
    const int sl = slave_index(r_.settings, a);
    const bool on_limit = (r_.settings.axes[a].shared_limit && r_.axis(a).sensor) ||
                          (sl >= 0 && r_.settings.axes[static_cast<std::size_t>(sl)].shared_limit &&
                           r_.axis(static_cast<std::size_t>(sl)).sensor);
    if (master_index(r_.settings, a) < 0 && homed_axis(a) && e.soft_limits_enable && e.mode != HomingMode::disabled &&
        !on_limit)
      cand.push_back(a);
  }
  if (cand.empty() || r_.status().alarm) return;
  const std::size_t a = cand[static_cast<std::size_t>(d_.integer(0, static_cast<int>(cand.size()) - 1))];
  const int slave = slave_index(r_.settings, a);
  const AxisMask movers = static_cast<AxisMask>(axis_bit(a) | (slave >= 0 ? axis_bit(static_cast<std::size_t>(slave)) : 0));
  const AxisSettings e = effective(r_.settings, a);
  Causes causes;
  if (e.shared_limit || (slave >= 0 && r_.settings.axes[static_cast<std::size_t>(slave)].shared_limit))
    causes.add("the jogged pair's shared-limit sensor", {AlarmCode::hard_limit}, movers);
  w_->clear_alarms_seen();
  w_->set_outside_movers(movers);
  const int dir = d_.chance(0.5) ? 1 : -1;
  say(std::string("jog ") + kAxisUpper[a] + (dir > 0 ? " +" : " -"));
  r_.jog(a, dir);
  r_.run_for(d_.u(0.05, 1.0));
  r_.release_jogs();
  settle(10);
  if (!r_.status().alarm && homed_axis(a)) {
    const double target = r_.axis(a).position_mm + d_.u(-40, 40);
    const bool outside = target < e.soft_limit_min_mm || target > e.soft_limit_max_mm;
    say(std::string("move ") + kAxisUpper[a] + " to " + std::to_string(target));
    r_.move(a, target);
    const CommandResult res = r_.status().last_command_result;
    if (outside && res != CommandResult::refused_soft_limit) w_->fail("a move outside the soft limits was not refused", std::string(command_result_name(res)));
    if (!outside && res != CommandResult::accepted) w_->fail("a move inside the soft limits was refused", std::string(command_result_name(res)));
    r_.run_until([&] { return (!r_.any_moving() && r_.axis(a).phase != Phase::move) || !ok(); }, 120);
    settle(10);
    if (!outside && !r_.status().alarm && ok() && std::abs(r_.axis(a).position_mm - target) > 1e-9)
      w_->fail("a move did not arrive", std::to_string(r_.axis(a).position_mm) + " for " + std::to_string(target));
    if (ok()) acts_ |= act::jog_and_move;
  }
  if (slave >= 0 && d_.chance(0.3) && !r_.status().alarm) {
    r_.move(static_cast<std::size_t>(slave), r_.axis(static_cast<std::size_t>(slave)).position_mm + 1);
    if (r_.status().last_command_result != CommandResult::refused_slave_axis)
      w_->fail("a move commanded to a slave was not refused", std::string(command_result_name(r_.status().last_command_result)));
    settle(10);
  }
  w_->set_outside_movers(0);
  if (auto u = explain(*w_, causes, r_.settings)) w_->fail(u->what + " during jogs and moves", u->detail);
}

// A shared-limit axis jogged into its own sensor: the trip must be recoverable.
void Run::hard_limit_recovery() {
  std::vector<std::size_t> cand;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisSettings e = effective(r_.settings, a);
    // A sensor the simulator has blinded (stuck inactive, an open NO circuit)
    // cannot trip: the jog would run into the stop with nothing to tell the engine.
    if (master_index(r_.settings, a) < 0 && homed_axis(a) && r_.settings.axes[a].shared_limit && !mode_is_pushing(e.mode) &&
        !r_.axis(a).sensor && r_.sim().axis_config(a).fault == sim::Fault::none)
      cand.push_back(a);
  }
  if (cand.empty() || r_.status().alarm) return;
  const std::size_t a = cand[static_cast<std::size_t>(d_.integer(0, static_cast<int>(cand.size()) - 1))];
  const int slave = slave_index(r_.settings, a);
  const AxisMask movers = static_cast<AxisMask>(axis_bit(a) | (slave >= 0 ? axis_bit(static_cast<std::size_t>(slave)) : 0));
  const int toward = dir_of(effective(r_.settings, a)) > 0 ? 1 : -1;
  w_->clear_alarms_seen();
  w_->set_outside_movers(movers);
  say(std::string("jog ") + kAxisUpper[a] + " toward its shared-limit sensor");
  r_.jog(a, toward);
  r_.run_until([&] { return r_.status().alarm || !ok(); }, 10);
  r_.release_jogs();
  settle(10);
  {
    Causes causes;
    // The jogged axis, or its slave riding along, meets its sensor first.
    causes.add(std::string(1, kAxisUpper[a]) + "'s shared-limit sensor or its slave's", {AlarmCode::hard_limit}, movers);
    if (auto u = explain(*w_, causes, r_.settings)) w_->fail(u->what + " jogging into a shared-limit sensor", u->detail);
  }
  if (r_.axis(a).alarm.code != AlarmCode::hard_limit || !ok()) {
    w_->set_outside_movers(0);
    return;  // the soft limits kept it off its sensor
  }
  say("hard limit tripped; reset");
  w_->set_outside_movers(0);
  r_.reset_alarm();
  if (r_.status().last_command_result != CommandResult::accepted)
    w_->fail("after a hard-limit trip the reset was refused", std::string(command_result_name(r_.status().last_command_result)));
  for (int i = 0; i < 3; ++i) step();
  if (r_.status().alarm) {
    w_->fail("after a hard-limit trip the alarm latched again right after the reset");
    return;
  }
  // Toward the sensor: refused, nothing moves.
  w_->set_outside_movers(movers);
  const double x0 = r_.actual(a);
  say("jog toward the tripped sensor");
  r_.jog(a, toward);
  r_.run_for(0.3);
  r_.release_jogs();
  settle(10);
  if (std::abs(r_.actual(a) - x0) > 1e-9) w_->fail("a jog toward a tripped shared-limit sensor moved the axis");
  if (r_.status().alarm) {
    say("alarm again; reset");
    r_.reset_alarm();
    for (int i = 0; i < 3; ++i) step();
  }
  // Away from it: allowed until it releases.
  say("jog away from the tripped sensor");
  const double x1 = r_.actual(a);
  r_.jog(a, -toward);
  const bool released = r_.run_until([&] { return (!r_.sim().sensor_active(a) && !r_.axis(a).sensor) || r_.status().alarm || !ok(); }, 20);
  r_.release_jogs();
  settle(10);
  if (std::abs(r_.actual(a) - x1) <= 1e-9) w_->fail("a jog away from a tripped shared-limit sensor did not move the axis",
                                                   std::string(command_result_name(r_.status().last_command_result)));
  else if (!released || r_.status().alarm) w_->fail("a jog away from a tripped shared-limit sensor did not release it");
  else acts_ |= act::hard_limit_recovered;
  w_->set_outside_movers(0);
}

// Steps lost on plain switch axes, then a re-home: the correction shows them.
void Run::lost_steps() {
  std::vector<std::size_t> cand;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisSettings& s = r_.settings.axes[a];
    // Homed on its edge (not assigned unsequenced): the correction then measures the loss.
    if (m_.plan[a].role == Role::plain && mode_uses_switch(s.mode) && !mode_is_pushing(s.mode) && homed_axis(a) &&
        w_->truth[a].has_rest && !m_.plan[a].short_cam)
      cand.push_back(a);
  }
  if (cand.empty() || r_.status().alarm) return;
  const std::size_t a = cand[static_cast<std::size_t>(d_.integer(0, static_cast<int>(cand.size()) - 1))];
  const AxisSettings& s = r_.settings.axes[a];
  const double dir = dir_of(s);
  // Never across the cam's edge: a carriage that jumps over it would show the
  // engine an edge where there is none (the simulator reports the jump as one).
  if (r_.sim().sensor_active(a)) return;
  const auto& c = r_.sim().axis_config(a);
  const double to_cam = dir > 0 ? c.sensor_min_mm - r_.actual(a) : r_.actual(a) - c.sensor_max_mm;
  const double lost = d_.chance(0.5) ? -dir * d_.u(0, 3) : dir * d_.u(0, std::min(s.pull_off_mm, 0.8 * to_cam));
  say(std::string("lose ") + std::to_string(lost) + " on " + kAxisUpper[a]);
  r_.sim().lose_steps(a, lost);
  w_->carriage_jumped(a);
  if (r_.sim().at_hard_stop(a)) return;
  // A home-all measures the loss only where it homes the axis on its edge: an
  // unsequenced axis is assigned where it stands (correction 0); home it alone.
  const bool all = d_.chance(0.5) && (plan_cycle(r_.settings, true, 0).covered & axis_bit(a));
  if (!cycle(all, axis_bit(a), {}, false)) return;
  const double tol = 2 * rig::edge_tolerance_mm(s, 0.001) + 1e-9;
  if (r_.sim().axis_config(a).noise_mm == 0 && std::abs(r_.axis(a).home_correction_mm - lost) > tol)
    w_->fail("the home correction differs from the steps lost",
             std::to_string(r_.axis(a).home_correction_mm) + " for " + std::to_string(lost));
  else if (r_.sim().axis_config(a).noise_mm == 0)
    acts_ |= act::lost_steps_corrected;
}

// Refused settings with a slave that cannot be one: a jog of the axis it
// names must not carry it along either.
void Run::jog_invalid_slave() {
  const Invalid v = m_.invalid;
  if (v != Invalid::slave_of_disabled && v != Invalid::slave_of_slave && v != Invalid::two_slaves &&
      v != Invalid::master_not_on_switch && v != Invalid::slave_disabled && v != Invalid::slave_without_sensor)
    return;
  const std::size_t a = m_.invalid_axis;
  const int named = static_cast<int>(r_.settings.axes[a].slave_of) - 1;
  if (named < 0 || named >= static_cast<int>(kAxisCount) || named == static_cast<int>(a) || r_.status().estop) return;
  const std::size_t mi = static_cast<std::size_t>(named);
  AxisMask movers = axis_bit(mi);
  for (std::size_t s = 0; s < kAxisCount; ++s)
    if (static_cast<int>(r_.settings.axes[s].slave_of) - 1 == named) movers |= axis_bit(s);
  const double x = r_.actual(a);
  r_.reset_alarm();
  w_->set_outside_movers(movers);
  say(std::string("jog ") + kAxisUpper[mi] + ", which " + kAxisUpper[a] + " names as its master");
  r_.jog(mi, dir_of(r_.settings.axes[mi]) > 0 ? -1 : 1);
  const double end = r_.sim().time_s() + 0.2;
  while (r_.sim().time_s() < end && ok()) {
    step();
    if (std::abs(r_.actual(a) - x) > 1e-9)
      w_->fail(std::string("a slave the configuration check refuses (") + invalid_name(v) + ") followed its master's jog");
  }
  r_.release_jogs();
  settle(10);
  w_->set_outside_movers(0);
}

}  // namespace campaign
