// Acts at end-of-travel limit switches (docs/limit-switches.md "Hard
// limits"): a homed axis jogged or moved into one must stop with
// limit_switch, within its stopping distance (the watch holds every period
// to that); the reset is taken while it stands on the switch, a jog further
// onto it is refused and moves nothing, a jog away is allowed until the
// switch releases. From their own dice (stream 15): runs without such an
// axis draw as before.
#include "homing/motion.hpp"
#include "run.hpp"

namespace campaign {

namespace {

constexpr double kReducedJog_mm_per_s = 100.0 / 60.0;  // the slowest a jog away may run (jog_reduced)

}  // namespace

bool Run::on_limit_switch(std::size_t a) {
  return r_.settings.axes[a].limits_fitted && r_.sim().axis_config(a).fault == sim::Fault::none &&
         (r_.sim().limit_active(a, false) || r_.sim().limit_active(a, true));
}

void Run::limit_switch_trip() {
  if (r_.status().alarm) return;
  struct Candidate {
    std::size_t axis;
    int side;
    double distance;
  };
  std::vector<Candidate> cand;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisSettings e = effective(r_.settings, a);
    if (!e.limits_fitted || master_index(r_.settings, a) >= 0 || slave_index(r_.settings, a) >= 0 || !homed_axis(a) ||
        r_.sim().axis_config(a).fault != sim::Fault::none || on_limit_switch(a))
      continue;
    for (const int side : {-1, 1}) {
      // A switch axis toward its sensor would cross its cam, to a place its
      // seek cannot home from; a home cam's search reverses: either end.
      if (e.mode != HomingMode::home_cam && side == static_cast<int>(dir_of(e))) continue;
      const auto& c = r_.sim().axis_config(a);
      const double sw = side > 0 ? c.limit_max_mm : c.limit_min_mm;
      const double distance = (sw - r_.actual(a)) * side;
      // Near enough to reach at jog feedrate in a few seconds of machine time.
      if (distance < 0.5 || distance / mm_per_min_to_mm_per_s(e.jog_feedrate_mm_per_min) > 30) continue;
      // Soft limits on: the switch must lie inside them, or they stop the jog first.
      const double sw_machine = sw + w_->truth[a].offset;
      if (e.soft_limits_enable &&
          (side > 0 ? sw_machine > e.soft_limit_max_mm - 0.5 : sw_machine < e.soft_limit_min_mm + 0.5))
        continue;
      cand.push_back({a, side, distance});
    }
  }
  if (cand.empty() || !limit_acts_.chance(0.3)) return;
  const Candidate k = cand[static_cast<std::size_t>(limit_acts_.integer(0, static_cast<int>(cand.size()) - 1))];
  const std::size_t a = k.axis;
  const AxisMask bit = axis_bit(a);
  const AxisSettings e = effective(r_.settings, a);
  const std::string x(1, kAxisUpper[a]);
  const auto& c = r_.sim().axis_config(a);
  const double sw = k.side > 0 ? c.limit_max_mm : c.limit_min_mm;
  const double jog_v = mm_per_min_to_mm_per_s(e.jog_feedrate_mm_per_min);
  const bool by_move = limit_acts_.chance(0.5);
  Causes causes;
  limit_sensor_faults(causes);
  causes.add(x + "'s limit switch, " + (by_move ? "moved" : "jogged") + " into", {AlarmCode::limit_switch}, bit, true);
  w_->clear_alarms_seen();
  w_->set_outside_movers(bit);
  if (by_move) {
    // Past the switch, inside the soft limits.
    const double sw_machine = sw + w_->truth[a].offset;
    double beyond = limit_acts_.u(0.5, 5);
    if (e.soft_limits_enable)
      beyond = std::min(beyond, k.side > 0 ? e.soft_limit_max_mm - sw_machine : sw_machine - e.soft_limit_min_mm);
    const double target = sw_machine + k.side * beyond;
    say("move " + x + " into its limit switch at " + std::to_string(sw) + ", to " + std::to_string(target));
    r_.move(a, target);
    if (r_.status().last_command_result != CommandResult::accepted)
      w_->fail("a move into a limit switch inside the soft limits was refused",
               std::string(command_result_name(r_.status().last_command_result)));
  } else {
    say("jog " + x + " toward its limit switch at " + std::to_string(sw));
    r_.jog(a, k.side);
  }
  r_.run_until([&] { return r_.status().alarm || !ok(); }, k.distance / jog_v + 5);
  r_.release_jogs();
  settle(10);
  w_->set_outside_movers(0);
  mark(by_move ? "moved into a limit switch" : "jogged into a limit switch",
       static_cast<std::uint8_t>(seen::present | ((w_->axis_alarms[a] & alarm_bit(AlarmCode::limit_switch)) ? seen::alarmed : 0)));
  if (auto u = explain(*w_, causes, r_.settings)) {
    w_->fail(u->what + " at a limit switch", u->detail);
    return;
  }
  if (r_.axis(a).alarm.code != AlarmCode::limit_switch || !ok()) return;  // another cause stopped it first

  say("limit switch tripped; reset");
  r_.reset_alarm();
  if (r_.status().last_command_result != CommandResult::accepted)
    w_->fail("after a limit switch trip the reset was refused",
             std::string(command_result_name(r_.status().last_command_result)));
  for (int i = 0; i < 3; ++i) step();
  if (r_.status().alarm) {
    w_->fail("after a limit switch trip the alarm latched again right after the reset", alarm_list(w_->alarms_seen));
    return;
  }
  // Further onto it: refused, nothing moves.
  w_->set_outside_movers(bit);
  const double x0 = r_.actual(a);
  say("jog " + x + " further onto the tripped limit switch");
  r_.jog(a, k.side);
  step();
  const CommandResult further = r_.status().last_command_result;
  r_.run_for(0.3);
  r_.release_jogs();
  settle(10);
  if (further != CommandResult::refused_hard_limit)
    w_->fail("a jog further onto a tripped limit switch was not refused", std::string(command_result_name(further)));
  if (std::abs(r_.actual(a) - x0) > 1e-9) w_->fail("a jog further onto a tripped limit switch moved the axis");
  if (r_.status().alarm) w_->fail("a refused jog onto a tripped limit switch raised an alarm", alarm_list(w_->alarms_seen));
  w_->set_outside_movers(0);
  if (!ok()) return;
  jog_off_limit_switch(a, -k.side);
  if (ok()) acts_ |= act::limit_switch_recovered;
}

// Away from the limit switch it stands on: accepted, and it runs until the
// switch releases (at the reduced jog speed at worst), with no alarm.
void Run::jog_off_limit_switch(std::size_t a, int away) {
  const AxisMask bit = axis_bit(a);
  const std::string x(1, kAxisUpper[a]);
  const auto& c = r_.sim().axis_config(a);
  const double past = std::max(c.limit_min_mm - r_.actual(a), r_.actual(a) - c.limit_max_mm);
  w_->set_outside_movers(bit);
  say("jog " + x + " away from its limit switch");
  const double x1 = r_.actual(a);
  r_.jog(a, away);
  step();
  const CommandResult res = r_.status().last_command_result;
  const bool released = r_.run_until(
      [&] { return (!r_.sim().limit_active(a, false) && !r_.sim().limit_active(a, true)) || r_.status().alarm || !ok(); },
      std::max(past, 0.0) / kReducedJog_mm_per_s + 5);
  r_.release_jogs();
  settle(10);
  w_->set_outside_movers(0);
  if (res != CommandResult::accepted)
    w_->fail("a jog away from a tripped limit switch was refused", std::string(command_result_name(res)));
  else if (std::abs(r_.actual(a) - x1) <= 1e-9)
    w_->fail("a jog away from a tripped limit switch did not move the axis");
  else if (!released || r_.status().alarm)
    w_->fail("a jog away from a tripped limit switch did not release it", alarm_list(w_->alarms_seen));
}

}  // namespace campaign
