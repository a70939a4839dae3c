#include "check.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "homing/phases.hpp"
#include "homing/gantry.hpp"
#include "homing/motion.hpp"
#include "homing/sequence.hpp"
#include "homing/settings_check.hpp"

namespace homingctl {

using homing::HomingMode;

namespace {

// Time of a point-to-point move of `d` at most `v` with acceleration `a` (trapezoid or triangle).
double move_time(double d, double v, double a) {
  d = std::abs(d);
  if (d <= 0 || v <= 0 || a <= 0) return 0;
  if (d <= v * v / a) return 2 * std::sqrt(d / a);
  return d / v + v / a;
}

}  // namespace

bool CheckReport::ok() const {
  return std::none_of(axes.begin(), axes.end(), [](const AxisCheck& a) { return a.fault.has_value(); });
}

CheckReport check_settings(const homing::Settings& settings,
                           const std::array<std::optional<TriggerCam>, homing::kAxisCount>& cams) {
  CheckReport r;
  // The engine's rule set, and the settings each axis really moves with (a
  // slave its master's): the figures below are the ones the engine uses.
  const homing::SettingsFaults faults = homing::check_settings(settings);
  const homing::Settings moves = homing::motion_settings(settings);
  for (std::size_t i = 0; i < homing::kAxisCount; ++i) {
    const homing::AxisSettings& s = moves.axes[i];
    AxisCheck c;
    c.axis = i;
    c.enabled = s.mode != HomingMode::disabled || faults[i];
    c.stop_distance_mm = homing::seek_stop_distance_mm(s);
    c.max_stop_distance_mm = s.max_stop_distance_mm;
    c.unit = homing::axis_unit(settings, i);  // a slave's is its master's
    const std::string& u = c.unit;
    if (!c.enabled) {
      r.axes.push_back(c);
      continue;
    }
    if (const auto& f = faults[i]) c.fault = homing::describe_fault(*f, settings);
    const double a = s.acceleration_mm_per_s2;
    const double seek_v = homing::mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min);
    const double latch_v = homing::mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
    const double latch_stop = a > 0 ? homing::stop_distance_mm(latch_v, a) : 0;
    auto phase = [&](homing::Phase p, double t) {
      if (t > 0) c.phases.emplace_back(std::string(homing::phase_name(p)), t);
    };
    const bool final_move = homing::final_move_wanted(s);
    // The worst-case time of each phase the axis's method runs (modes.hpp).
    using homing::Phase;
    for (const Phase p : homing::mode_row(s.mode).phase_list()) {
      switch (p) {
        case Phase::pre_move:
          if (s.pre_move_mode == homing::PreMove::always) phase(p, move_time(s.pre_move_distance_mm, seek_v, a));
          break;
        case Phase::seek:
          c.seek_worst_s = move_time(s.max_seek_travel_mm, seek_v, a);
          phase(p, c.seek_worst_s);
          break;
        case Phase::stop:
        case Phase::cam_stop: phase(p, a > 0 ? seek_v / a + s.debounce_ms / 1000.0 : 0); break;
        // A home cam: out to the limit switch ahead over max_seek_travel at
        // worst, braking there, and back over max_seek_travel again.
        case Phase::cam_seek:
          c.seek_worst_s = move_time(s.max_seek_travel_mm, seek_v, a);
          phase(p, c.seek_worst_s);
          break;
        case Phase::limit_reversal: {
          const double t = (a > 0 ? seek_v / a : 0) + move_time(s.max_seek_travel_mm, seek_v, a);
          c.seek_worst_s += t;
          phase(p, t);
          break;
        }
        // Off the cam toward cam_edge: from the stop on it, and across the
        // whole cam when its far edge is the reference (not known without the
        // simulator unit: max_backoff, the most the latch may run).
        case Phase::cam_latch: {
          double d = c.stop_distance_mm + latch_stop;
          if (s.cam_edge == homing::CamEdge::ahead)
            d = cams[i] ? d + (cams[i]->max_mm - cams[i]->min_mm) + cams[i]->hysteresis_mm : s.max_backoff_mm;
          phase(p, move_time(d, latch_v, a) + s.debounce_ms / 1000.0);
          break;
        }
        case Phase::push: phase(p, move_time(s.push_distance_mm, latch_v, a)); break;
        case Phase::push_to_stop:
          // Bounded twice: the travel at latch feedrate, and stall_timeout_ms.
          c.seek_worst_s = std::min(move_time(s.max_seek_travel_mm, latch_v, a), s.stall_timeout_ms / 1000.0);
          phase(p, c.seek_worst_s);
          break;
        case Phase::back_off:
          phase(p, move_time(c.stop_distance_mm + latch_stop, latch_v, a) + s.debounce_ms / 1000.0);
          break;
        case Phase::reapproach: phase(p, move_time(2 * latch_stop + 0.1, latch_v, a)); break;
        case Phase::index: phase(p, move_time(homing::index_search_mm(s), latch_v, a)); break;
        case Phase::pull_off: phase(p, move_time(s.pull_off_mm + latch_stop, seek_v, a)); break;
        case Phase::final_move:
          if (final_move) phase(p, move_time(s.final_position_mm - s.home_position_mm, seek_v, a));
          break;
        // The drive's own homing takes what it takes: its time limit is the worst case.
        case Phase::drive_homing: phase(p, s.drive_home_timeout_s); break;
        default: break;  // no motion of its own (assign) or not a phase of a method
      }
    }
    for (const auto& [name, t] : c.phases)
      if (name != "seek" && name != "push_to_stop" && name != "cam_seek" && name != "limit_reversal")
        c.after_trigger_s += t;
    if (s.limits_fitted) {
      c.limits = true;
      c.limit_stop_distance_mm = homing::limit_stop_distance_mm(s);
      c.limit_overtravel_mm = s.limit_overtravel_mm;
    }
    // What the row needs wired, with the stop detection the axis chose.
    // Limit switches fitted are read on every method (hard limits), not only by one that reverses at them.
    for (const homing::SignalInfo& sig : homing::kSignalInfo) {
      const bool limit = sig.signal == homing::Signal::limit_min || sig.signal == homing::Signal::limit_max;
      if (homing::needs_signal(s, sig.signal) || (limit && s.limits_fitted)) c.signals.emplace_back(sig.name);
    }
    if (homing::mode_row(s.mode).detects_stop()) {
      c.stop_detection = homing::name_of(s.stall_detect);
      if (homing::detects_stop_by_following_error(s)) c.max_following_error_mm = s.max_following_error_mm;
    }

    // Warnings the engine's check does not refuse.
    if (homing::mode_uses_switch(s.mode)) {
      if (s.max_stop_distance_mm > 0 && c.stop_distance_mm > 0.8 * s.max_stop_distance_mm && !c.fault)
        c.warnings.push_back(fmt::format("stop distance {:.3f} {} uses {:.0f}% of max_stop_distance {:g} {}: little margin",
                                         c.stop_distance_mm, u, 100 * c.stop_distance_mm / s.max_stop_distance_mm,
                                         s.max_stop_distance_mm, u));
      if (s.latch_feedrate_mm_per_min >= s.seek_feedrate_mm_per_min)
        c.warnings.push_back(fmt::format("latch_feedrate {:g} is not slower than seek_feedrate {:g}: the edge is "
                                         "located no more precisely than during the seek",
                                         s.latch_feedrate_mm_per_min, s.seek_feedrate_mm_per_min));
      if (cams[i]) {
        const double len = cams[i]->max_mm - cams[i]->min_mm;
        if (len < c.stop_distance_mm)
          c.warnings.push_back(fmt::format("the trigger (cam {:.3f} {} long) is shorter than the stop distance "
                                           "{:.3f} {}: the sensor releases while stopping (overrun_during_stop)",
                                           len, u, c.stop_distance_mm, u));
      } else {
        c.warnings.push_back(fmt::format("the trigger cam must be longer than the stop distance {:.3f} {} "
                                         "(not known to the module: measure it)", c.stop_distance_mm, u));
      }
      if (s.max_backoff_mm < c.stop_distance_mm + latch_stop)
        c.warnings.push_back(fmt::format("max_backoff {:g} {} is shorter than the stop distance plus the latch stop "
                                         "({:.3f} {}): back-off may end before the sensor releases (not_released)",
                                         s.max_backoff_mm, u, c.stop_distance_mm + latch_stop, u));
      if (s.pull_off_mm == 0)
        c.warnings.push_back("pull_off is 0: the axis rests on the sensor edge and the sensor may flicker");
    }
    if (c.limits && !c.fault && c.limit_stop_distance_mm > 0.8 * s.limit_overtravel_mm)
      c.warnings.push_back(fmt::format("the stop past a limit switch {:.3f} {} uses {:.0f}% of limit_overtravel {:g} {}: "
                                       "little margin before the mechanical stop",
                                       c.limit_stop_distance_mm, u, 100 * c.limit_stop_distance_mm / s.limit_overtravel_mm,
                                       s.limit_overtravel_mm, u));
    if (homing::mode_row(s.mode).runs(Phase::limit_reversal) && cams[i]) {
      const TriggerCam& k = *cams[i];
      const double travel = k.limit_max_mm - k.limit_min_mm;
      const double len = k.max_mm - k.min_mm;
      if (k.max_mm <= k.limit_min_mm || k.min_mm >= k.limit_max_mm)
        c.warnings.push_back(fmt::format("the home cam [{:g}, {:g}] {} lies outside the limit switches at {:g} and {:g} {}: "
                                         "the search cannot find it (cam_not_found)",
                                         k.min_mm, k.max_mm, u, k.limit_min_mm, k.limit_max_mm, u));
      else if (travel < 1e8 && s.max_seek_travel_mm < travel)
        c.warnings.push_back(fmt::format("max_seek_travel {:g} {} is shorter than the travel between the limit switches "
                                         "{:.3f} {}: the search back from one switch may end before the cam or the other "
                                         "switch (sensor_not_found)",
                                         s.max_seek_travel_mm, u, travel, u));
      const double latch = c.stop_distance_mm + latch_stop + len + k.hysteresis_mm;
      if (s.cam_edge == homing::CamEdge::ahead && s.max_backoff_mm < latch)
        c.warnings.push_back(fmt::format("max_backoff {:g} {} is shorter than the cam's length plus the stop ({:.3f} {}): "
                                         "the latch toward its far edge may end on the cam (not_released)",
                                         s.max_backoff_mm, u, latch, u));
    }
    const bool outside_home = s.home_position_mm < s.soft_limit_min_mm || s.home_position_mm > s.soft_limit_max_mm;
    if (outside_home)
      c.warnings.push_back(fmt::format("home_position {:g} {} is outside the soft limits [{:g}, {:g}]{}",
                                       s.home_position_mm, u, s.soft_limit_min_mm, s.soft_limit_max_mm,
                                       s.soft_limits_enable ? "" : " (soft limits are off now; enabling them will be refused)"));
    if (final_move && (s.final_position_mm < s.soft_limit_min_mm || s.final_position_mm > s.soft_limit_max_mm))
      c.warnings.push_back(fmt::format("final_position {:g} {} is outside the soft limits [{:g}, {:g}]",
                                       s.final_position_mm, u, s.soft_limit_min_mm, s.soft_limit_max_mm));
    if (homing::mode_uses_switch(s.mode) && s.soft_limits_enable &&
        s.max_seek_travel_mm < s.soft_limit_max_mm - s.soft_limit_min_mm)
      c.warnings.push_back(fmt::format("max_seek_travel {:g} {} is shorter than the soft-limit range {:g} {}: from the "
                                       "far end the sensor may be out of reach",
                                       s.max_seek_travel_mm, u, s.soft_limit_max_mm - s.soft_limit_min_mm, u));
    r.axes.push_back(c);
  }

  // The sequence as the engine plans it: steps one after the other, axes of a
  // step together, slaves with their master.
  const homing::CyclePlan plan = homing::plan_cycle(settings, homing::kAllAxes, true);
  for (const homing::AxisMask mask : plan.steps) {
    double worst = 0;
    for (std::size_t i = 0; i < homing::kAxisCount; ++i)
      if ((mask & homing::axis_bit(i)) && r.axes[i].enabled)
        worst = std::max(worst, r.axes[i].seek_worst_s + r.axes[i].after_trigger_s);
    r.cycle_worst_s += worst;
  }
  for (std::size_t i = 0; i < homing::kAxisCount; ++i)
    if (r.axes[i].enabled && (plan.unsequenced & homing::axis_bit(i)) && homing::master_of(settings.axes[i]) < 0 &&
        homing::mode_uses_switch(settings.axes[i].mode))
      r.warnings.push_back(fmt::format("{} is in no sequence step: home-all assigns its home position without moving it",
                                       homing::kAxisUpper[i]));
  if (settings.global.watchdog_ms == 0)
    r.warnings.push_back("global.watchdog_ms is 0: motion started over Modbus does not stop when the host goes silent");
  return r;
}

std::string render_check(const CheckReport& r) {
  std::string out;
  out += fmt::format("{:<4} {:<26} {:>12} {:>13} {}\n", "axis", "stop distance / max", "seek worst", "after trigger",
                     "verdict");
  for (const AxisCheck& c : r.axes) {
    const std::string& u = c.unit;
    if (!c.enabled) {
      out += fmt::format("{:<4} disabled\n", homing::kAxisUpper[c.axis]);
      continue;
    }
    out += fmt::format("{:<4} {:<26} {:>10.1f} s {:>11.1f} s {}\n", homing::kAxisUpper[c.axis],
                       fmt::format("{:.3f} / {:g} {}", c.stop_distance_mm, c.max_stop_distance_mm, u), c.seek_worst_s,
                       c.after_trigger_s, c.fault ? "REFUSED" : (c.warnings.empty() ? "ok" : "ok, with warnings"));
    if (c.fault) out += fmt::format("     error: {}\n", *c.fault);
    if (c.limits)
      out += fmt::format("     limit switches: stop past one {:.3f} / overtravel {:g} {}\n", c.limit_stop_distance_mm,
                         c.limit_overtravel_mm, u);
    if (!c.phases.empty()) {
      std::string p;
      for (const auto& [name, t] : c.phases) p += fmt::format("{}{} {:.2f} s", p.empty() ? "" : ", ", name, t);
      out += fmt::format("     phases (estimate): {}\n", p);
    }
    if (!c.signals.empty()) {
      std::string wiring;
      for (const auto& name : c.signals) wiring += (wiring.empty() ? "" : ", ") + name;
      out += fmt::format("     wiring: {}\n", wiring);
    }
    if (c.stop_detection == homing::name_of(homing::StallDetect::following_error))
      out += fmt::format("     stop told by: following error above {:g} {} (the encoder; the stall input is not "
                         "read)\n", c.max_following_error_mm, u);
    else if (!c.stop_detection.empty())
      out += "     stop told by: the drive's stall input\n";
    for (const auto& w : c.warnings) out += fmt::format("     warning: {}\n", w);
  }
  out += fmt::format("expected home-all cycle: at most {:.1f} s (seeks over their whole max_seek_travel, a home "
                     "cam's both ways; usually much less)\n", r.cycle_worst_s);
  for (const auto& w : r.warnings) out += fmt::format("warning: {}\n", w);
  out += r.ok() ? "settings: ok\n" : "settings: homing will be REFUSED (see the errors above)\n";
  return out;
}

nlohmann::json check_json(const CheckReport& r) {
  nlohmann::json j;
  j["ok"] = r.ok();
  j["cycle_worst_s"] = r.cycle_worst_s;
  j["warnings"] = r.warnings;
  j["axes"] = nlohmann::json::array();
  for (const AxisCheck& c : r.axes) {
    nlohmann::json a{{"axis", std::string(homing::kAxisLetters[c.axis])}, {"enabled", c.enabled}, {"unit", c.unit}};
    if (c.enabled) {
      a["stop_distance"] = c.stop_distance_mm;
      a["max_stop_distance"] = c.max_stop_distance_mm;
      a["fault"] = c.fault ? nlohmann::json(*c.fault) : nlohmann::json(nullptr);
      a["seek_worst_s"] = c.seek_worst_s;
      a["after_trigger_s"] = c.after_trigger_s;
      if (c.limits) {
        a["limit_stop_distance"] = c.limit_stop_distance_mm;
        a["limit_overtravel"] = c.limit_overtravel_mm;
      }
      a["phases"] = nlohmann::json::object();
      for (const auto& [name, t] : c.phases) a["phases"][name] = t;
      a["warnings"] = c.warnings;
      a["signals"] = c.signals;
      a["stop_detection"] = c.stop_detection.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.stop_detection);
      if (c.max_following_error_mm > 0) a["max_following_error"] = c.max_following_error_mm;
    }
    j["axes"].push_back(a);
  }
  return j;
}

}  // namespace homingctl
