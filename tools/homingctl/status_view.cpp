#include "status_view.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "homing/gantry.hpp"
#include "homing/settings_check.hpp"

namespace homingctl {

namespace {
std::string ax(std::size_t a, std::string_view field) {
  return fmt::format("axis.{}.{}", homing::kAxisLetters[a], field);
}
}  // namespace

StatusView read_status(Connection& c, const homing::Settings& settings) {
  std::vector<const registers::Register*> regs;
  for (const char* n : {"status.state", "status.sequence_step", "status.homing_cycles", "status.heartbeat",
                        "status.last_command_result", "status.interlocks", "status.global_alarm", "status.alarm",
                        "status.homing", "status.estop"})
    regs.push_back(&register_named(n));
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    for (const char* f : {"homed", "sensor", "busy", "limit_min", "limit_max"}) regs.push_back(&register_named(ax(a, f)));
    if (settings.axes[a].mode == homing::HomingMode::disabled) continue;
    for (const char* f :
         {"phase", "alarm", "alarm_phase", "alarm_value", "alarm_side", "alarm_rack_at_start", "alarm_rule", "position", "velocity",
          "phase_distance", "stop_distance", "trust", "refcheck_error"})
      regs.push_back(&register_named(ax(a, f)));
  }
  const auto v = c.read_many(regs);
  auto get = [&](const std::string& n) { auto it = v.find(n); return it == v.end() ? 0 : it->second; };
  auto mm = [&](const std::string& n) { return static_cast<double>(get(n)) / 1000.0; };
  StatusView s;
  s.state = static_cast<homing::MachineState>(get("status.state"));
  s.sequence_step = static_cast<int>(get("status.sequence_step"));
  s.homing_cycles = static_cast<std::uint32_t>(get("status.homing_cycles"));
  s.heartbeat = static_cast<std::uint16_t>(get("status.heartbeat"));
  s.last_command_result = static_cast<homing::CommandResult>(get("status.last_command_result"));
  s.interlocks = static_cast<std::uint16_t>(get("status.interlocks"));
  s.global_alarm = static_cast<homing::AlarmCode>(get("status.global_alarm"));
  s.alarm = get("status.alarm") != 0;
  s.homing = get("status.homing") != 0;
  s.estop = get("status.estop") != 0;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    AxisView& x = s.axes[a];
    x.homed = get(ax(a, "homed")) != 0;
    x.sensor = get(ax(a, "sensor")) != 0;
    x.busy = get(ax(a, "busy")) != 0;
    x.limit_min = get(ax(a, "limit_min")) != 0;
    x.limit_max = get(ax(a, "limit_max")) != 0;
    x.phase = static_cast<homing::Phase>(get(ax(a, "phase")));
    x.alarm = static_cast<homing::AlarmCode>(get(ax(a, "alarm")));
    x.alarm_phase = static_cast<homing::Phase>(get(ax(a, "alarm_phase")));
    x.alarm_value = mm(ax(a, "alarm_value"));
    x.alarm_side = static_cast<homing::GantrySide>(get(ax(a, "alarm_side")));
    x.alarm_rack_at_start = mm(ax(a, "alarm_rack_at_start"));
    x.alarm_rule = static_cast<std::uint8_t>(get(ax(a, "alarm_rule")));
    x.position = mm(ax(a, "position"));
    x.velocity = mm(ax(a, "velocity"));
    x.phase_distance = mm(ax(a, "phase_distance"));
    x.stop_distance = mm(ax(a, "stop_distance"));
    x.trust = static_cast<homing::Trust>(get(ax(a, "trust")));
    x.refcheck_error = mm(ax(a, "refcheck_error"));
  }
  return s;
}

std::string alarm_text(std::size_t axis, const AxisView& a, const homing::Settings& settings) {
  if (a.alarm == homing::AlarmCode::none) return "";
  homing::Alarm alarm{};
  alarm.code = a.alarm;
  alarm.phase = a.alarm_phase;
  alarm.value = a.alarm_value;  // the figure the engine quoted when it raised the alarm
  alarm.side = a.alarm_side;
  alarm.rack_at_start_mm = a.alarm_rack_at_start;
  alarm.rule = a.alarm_rule;  // a limit alarm's end: the text names it
  if (a.alarm == homing::AlarmCode::settings_fault || a.alarm == homing::AlarmCode::slave_sensor_missing) {
    if (auto f = homing::check_axis(settings, axis)) {
      alarm.field = f->field;
      alarm.rule = static_cast<std::uint8_t>(f->rule);
      alarm.value = f->value;
    }
  }
  return homing::describe_alarm(axis, alarm, settings);
}

std::string global_alarm_text(homing::AlarmCode code, const homing::Settings& settings) {
  if (code == homing::AlarmCode::none) return "";
  homing::Alarm alarm{};
  alarm.code = code;
  std::string t = homing::describe_alarm(0, alarm, settings);
  // describe_alarm names an axis; a global alarm has none.
  if (t.rfind("X: ", 0) == 0) t = t.substr(3);
  return t;
}

std::string interlocks_text(std::uint16_t bits) {
  std::string s;
  for (int b = 0; b < homing::interlock::kCount; ++b)
    if (bits & (1u << b)) s += fmt::format("{}{}", s.empty() ? "" : ", ", homing::interlock_name(b));
  return s.empty() ? "none" : s;
}

double phase_bound_mm(homing::Phase phase, const homing::AxisSettings& s) {
  using homing::Phase;
  switch (phase) {
    case Phase::seek: return s.max_seek_travel_mm;
    case Phase::stop: return s.max_stop_distance_mm;
    case Phase::back_off:
    case Phase::reapproach: return s.max_backoff_mm;
    case Phase::pull_off: return s.pull_off_mm;
    case Phase::pre_move: return s.pre_move_distance_mm;
    case Phase::push: return s.push_distance_mm;
    case Phase::index: return homing::index_search_mm(s);
    default: return 0;
  }
}

std::string progress_bar(double done, double bound, int width) {
  const double f = bound > 0 ? std::clamp(std::abs(done) / bound, 0.0, 1.0) : 0.0;
  const int n = static_cast<int>(std::lround(f * width));
  return "[" + std::string(static_cast<std::size_t>(n), '#') + std::string(static_cast<std::size_t>(width - n), '.') + "]";
}

std::string render_status(const StatusView& s, const homing::Settings& settings, bool progress) {
  std::string out;
  out += fmt::format("{:<4} {:<18} {:<11} {:>14} {:<5} {:<19} {:<6} {:<7} {}\n", "axis", "mode", "phase", "position",
                     "homed", "trust", "sensor", "limits", "alarm");
  const homing::Settings moves = homing::motion_settings(settings);  // a slave's bounds are its master's
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const AxisView& x = s.axes[a];
    const auto& st = settings.axes[a];
    const bool disabled = st.mode == homing::HomingMode::disabled;
    const std::string pos = disabled ? "-" : fmt::format("{:.3f} {}", x.position, homing::axis_unit(settings, a));
    std::string alarm = x.alarm == homing::AlarmCode::none
                            ? "-"
                            : fmt::format("{}: {}", homing::alarm_name(x.alarm), alarm_text(a, x, settings));
    // The limit switches: "-" none fitted, "off", "-on" (negative end active), "+on", "- +" (both).
    const std::string limits = disabled || !st.limits_fitted ? "-"
                               : x.limit_min && x.limit_max ? "- +"
                               : x.limit_min                ? "-on"
                               : x.limit_max                ? "+on"
                                                            : "off";
    out += fmt::format("{:<4} {:<18} {:<11} {:>14} {:<5} {:<19} {:<6} {:<7} {}\n", homing::kAxisUpper[a],
                       homing::mode_name(st.mode), disabled ? "-" : std::string(homing::phase_name(x.phase)), pos,
                       x.homed ? "yes" : "no", disabled ? "-" : std::string(homing::name_of(x.trust)),
                       disabled ? "-" : (x.sensor ? "on" : "off"), limits, alarm);
    if (progress && !disabled && x.busy) {
      const homing::AxisSettings& homes_with = homing::is_commutator_slave(settings, a)
                                                   ? homing::commutator_slave_homing(moves.axes[a])
                                                   : moves.axes[a];
      const double bound = phase_bound_mm(x.phase, homes_with);
      if (bound > 0)
        out += fmt::format("     {} {} {:.3f} / {:g} {}\n", progress_bar(x.phase_distance, bound, 30),
                           homing::phase_name(x.phase), std::abs(x.phase_distance), bound, homing::axis_unit(settings, a));
      else
        out += fmt::format("     {} {:.3f} {}\n", homing::phase_name(x.phase), std::abs(x.phase_distance),
                           homing::axis_unit(settings, a));
    }
  }
  out += fmt::format("state: {}", homing::state_name(s.state));
  if (s.sequence_step) out += fmt::format("   sequence step: {}", s.sequence_step);
  out += fmt::format("   homing cycles: {}   last command: {}\n", s.homing_cycles,
                     homing::command_result_name(s.last_command_result));
  out += fmt::format("blocking motion: {}\n", s.interlocks == 0 ? std::string("nothing (free to move)")
                                                                   : interlocks_text(s.interlocks));
  // limit_active says "jog away from it"; with both switches active no
  // direction is away, and the cause is almost always the wiring.
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const auto& st = settings.axes[a];
    if (st.mode == homing::HomingMode::disabled || !st.limits_fitted || !s.axes[a].limit_min || !s.axes[a].limit_max)
      continue;
    out += fmt::format("{}: both limit switches read active: no direction is away from them, nothing jogs or moves; "
                       "check the wiring (a broken wire to normally-closed switches) and axis.{}.limits_nc\n",
                       homing::kAxisUpper[a], homing::kAxisLetters[a]);
  }
  if (s.global_alarm != homing::AlarmCode::none)
    out += fmt::format("alarm: {}: {}\n", homing::alarm_name(s.global_alarm), global_alarm_text(s.global_alarm, settings));
  return out;
}

std::string progress_line(const StatusView& s, const homing::Settings& settings, bool distances) {
  std::string axes;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const AxisView& x = s.axes[a];
    const bool moving_phase = x.phase != homing::Phase::idle && x.phase != homing::Phase::waiting &&
                              x.phase != homing::Phase::done;
    if (!x.busy || !moving_phase || settings.axes[a].mode == homing::HomingMode::disabled) continue;
    axes += fmt::format("{}{} {}", axes.empty() ? "" : ", ", homing::kAxisUpper[a], homing::phase_name(x.phase));
    if (!distances) continue;
    const double bound = phase_bound_mm(x.phase, settings.axes[a]);
    const double done = std::abs(x.phase_distance);
    axes += bound > 0 ? fmt::format(" {:.1f} / {:g} {}", std::min(done, bound), bound, homing::axis_unit(settings, a))
                      : fmt::format(" {:.1f} {}", done, homing::axis_unit(settings, a));
  }
  if (axes.empty()) return "";
  return s.sequence_step ? fmt::format("step {}: {}", s.sequence_step, axes) : axes;
}

nlohmann::json status_json(const StatusView& s, const homing::Settings& settings) {
  nlohmann::json j;
  j["state"] = std::string(homing::state_name(s.state));
  j["sequence_step"] = s.sequence_step;
  j["homing_cycles"] = s.homing_cycles;
  j["heartbeat"] = s.heartbeat;
  j["last_command_result"] = std::string(homing::command_result_name(s.last_command_result));
  j["interlocks"] = nlohmann::json::array();
  for (int b = 0; b < homing::interlock::kCount; ++b)
    if (s.interlocks & (1u << b)) j["interlocks"].push_back(std::string(homing::interlock_name(b)));
  j["alarm"] = s.alarm;
  j["homing"] = s.homing;
  j["estop"] = s.estop;
  j["global_alarm"] = s.global_alarm == homing::AlarmCode::none
                          ? nlohmann::json(nullptr)
                          : nlohmann::json{{"code", static_cast<int>(s.global_alarm)},
                                           {"name", std::string(homing::alarm_name(s.global_alarm))},
                                           {"text", global_alarm_text(s.global_alarm, settings)}};
  j["axes"] = nlohmann::json::array();
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const AxisView& x = s.axes[a];
    nlohmann::json e;
    e["axis"] = std::string(homing::kAxisLetters[a]);
    e["mode"] = std::string(homing::mode_name(settings.axes[a].mode));
    e["phase"] = std::string(homing::phase_name(x.phase));
    e["position"] = x.position;
    e["unit"] = std::string(homing::axis_unit(settings, a));
    e["homed"] = x.homed;
    e["sensor"] = x.sensor;
    if (settings.axes[a].limits_fitted) e["limits"] = {{"min", x.limit_min}, {"max", x.limit_max}};
    e["busy"] = x.busy;
    e["trust"] = std::string(homing::name_of(x.trust));
    e["refcheck_error"] = x.refcheck_error;
    if (x.alarm == homing::AlarmCode::none)
      e["alarm"] = nullptr;
    else
      e["alarm"] = {{"code", static_cast<int>(x.alarm)},
                    {"name", std::string(homing::alarm_name(x.alarm))},
                    {"phase", std::string(homing::phase_name(x.alarm_phase))},
                    {"side", std::string(homing::name_of(x.alarm_side))},
                    {"text", alarm_text(a, x, settings)}};
    if (x.busy) e["phase_distance"] = x.phase_distance;
    j["axes"].push_back(e);
  }
  return j;
}

}  // namespace homingctl
