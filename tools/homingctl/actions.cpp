#include "actions.hpp"

#include <fmt/format.h>

#include <unistd.h>

#include <chrono>
#include <iterator>
#include <thread>

#include "homing/status.hpp"
#include "homing/gantry.hpp"
#include "homing/measure.hpp"
#include "settings_io.hpp"
#include "status_view.hpp"
#include "values.hpp"

namespace homingctl {

using Clock = std::chrono::steady_clock;
using homing::CommandResult;

int axis_index(std::string_view letter) {
  for (std::size_t a = 0; a < homing::kAxisCount; ++a)
    if (letter.size() == 1 && std::tolower(static_cast<unsigned char>(letter[0])) == homing::kAxisLetters[a][0])
      return static_cast<int>(a);
  return -1;
}

std::string command_result_text(int r, int axis) {
  // The engine's own text (homing/status.hpp), the one HMIs show too, with
  // the axis named where the table says <a> (register names are lower case).
  const auto& table = homing::kCommandResultInfo;
  if (r < 0 || r >= std::ssize(table)) return fmt::format("result {}", r);
  std::string text(table[r].text);
  if (axis >= 0 && axis < static_cast<int>(homing::kAxisCount))
    for (std::size_t at = text.find("<a>"); at != std::string::npos; at = text.find("<a>", at))
      text.replace(at, 3, homing::kAxisLetters[static_cast<std::size_t>(axis)]);
  return text;
}

namespace {

struct Session {
  Connection& c;
  const ActionOptions& o;
  homing::Settings settings;
  std::uint16_t hb = 0;

  Session(Connection& conn, const ActionOptions& opts) : c(conn), o(opts), settings(read_settings(conn)) {
    hb = static_cast<std::uint16_t>(c.read("status.heartbeat"));
  }

  void beat() {
    if (settings.global.watchdog_ms == 0) return;
    (void)c.write("host.heartbeat", ++hb);
  }

  // Waits until the control loop has published three new snapshots: the
  // command was taken in one of those periods (the loop takes its mailbox
  // with try_lock, and with --time-scale the heartbeat counts several engine
  // steps per period, so a heartbeat difference alone does not say enough).
  void let_loop_take(std::uint16_t h0) {
    const auto deadline = Clock::now() + std::chrono::seconds(2);
    std::uint16_t last = h0;
    int changes = 0;
    while (Clock::now() < deadline && changes < 3) {
      const auto h = static_cast<std::uint16_t>(c.read("status.heartbeat"));
      if (h != last) {
        ++changes;
        last = h;
      }
      if (changes < 3) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }

  // Writes a command coil (1) or command register; the command result after
  // the loop took it.
  std::expected<CommandResult, std::string> pulse(const std::string& command, std::int64_t value = 1) {
    beat();
    const auto h0 = static_cast<std::uint16_t>(c.read("status.heartbeat"));
    if (const int ex = c.write(command, value))
      return std::unexpected(fmt::format("writing {} refused: {}", command, exception_sentence(ex)));
    let_loop_take(h0);
    return static_cast<CommandResult>(c.read("status.last_command_result"));
  }

  // Polls until `done(status)` or the timeout; keeps the heartbeat alive.
  // With `progress`, what the cycle is doing goes to stderr while it runs
  // (stdout keeps the result line, or the JSON, for scripts): redrawn in
  // place on a terminal, one line per phase change otherwise.
  std::expected<StatusView, std::string> wait_for(const std::function<bool(const StatusView&)>& done,
                                                  bool progress = false) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(o.timeout_s);
    const bool tty = progress && ::isatty(STDERR_FILENO);
    std::string shown;
    for (;;) {
      beat();
      StatusView s = read_status(c, settings);
      if (progress) {
        // A terminal redraws the distances; a log gets a line per phase change.
        const std::string line = progress_line(s, settings, tty);
        if (line != shown && !line.empty()) {
          if (tty) fmt::print(stderr, "\r\033[K{}", line);
          else fmt::print(stderr, "{}\n", line);
        }
        shown = line;
      }
      if (done(s)) {
        if (tty && !shown.empty()) fmt::print(stderr, "\n");
        return s;
      }
      if (Clock::now() >= deadline)
        return std::unexpected(fmt::format("still {} after {:g} s: gave up waiting (the machine keeps going; "
                                           "`homingctl abort` stops it)",
                                           homing::state_name(s.state), o.timeout_s));
      std::this_thread::sleep_for(std::chrono::duration<double>(o.poll_s));
    }
  }

  std::vector<std::string> alarms(const StatusView& s) const {
    std::vector<std::string> out;
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (s.axes[a].alarm != homing::AlarmCode::none) out.push_back(alarm_text(a, s.axes[a], settings));
    if (s.global_alarm != homing::AlarmCode::none) out.push_back(global_alarm_text(s.global_alarm, settings));
    return out;
  }

  ActionResult refused(const std::string& what, CommandResult r, const StatusView* s = nullptr, int axis = -1) {
    ActionResult res;
    res.exit_code = 1;
    res.message = fmt::format("{} refused: {}", what, command_result_text(static_cast<int>(r), axis));
    StatusView st = s ? *s : read_status(c, settings);
    if (st.interlocks) res.message += fmt::format(" (blocking motion: {})", interlocks_text(st.interlocks));
    for (const auto& a : alarms(st)) res.message += "\n  " + a;
    res.json = {{"command", what}, {"ok", false}, {"result", std::string(homing::command_result_name(r))},
                {"message", res.message}};
    return res;
  }

  ActionResult finished(const std::string& what, const StatusView& s, bool alarm_is_failure = true) {
    ActionResult res;
    const auto al = alarms(s);
    res.json = {{"command", what}, {"state", std::string(homing::state_name(s.state))}};
    std::string pos;
    nlohmann::json positions = nlohmann::json::object();
    for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
      if (settings.axes[a].mode == homing::HomingMode::disabled) continue;
      pos += fmt::format("{}{} = {:.3f} {}{}", pos.empty() ? "" : ", ", homing::kAxisUpper[a], s.axes[a].position,
                         homing::axis_unit(settings, a), s.axes[a].homed ? "" : " (not homed)");
      positions[std::string(homing::kAxisLetters[a])] = s.axes[a].position;
    }
    res.json["positions"] = positions;
    res.json["alarms"] = al;
    if (!al.empty() && alarm_is_failure) {
      res.exit_code = 1;
      res.message = fmt::format("{} failed: {}", what, fmt::join(al, "\n  "));
      res.json["ok"] = false;
    } else {
      // The outcome first: the machine state alone ("not_homed" after a move)
      // reads like a failure when the command did what it was asked.
      res.message = fmt::format("{}: done, {}", what, pos);
      for (const auto& a : al) res.message += "\n  " + a;
      res.json["ok"] = true;
    }
    return res;
  }
};

bool at_rest(const StatusView& s) {
  if (s.homing) return false;
  for (const auto& a : s.axes)
    if (a.busy) return false;
  return s.state != homing::MachineState::homing && s.state != homing::MachineState::moving;
}

ActionResult failure(std::string message) {
  ActionResult r;
  r.exit_code = 1;
  r.json = {{"ok", false}, {"message", message}};
  r.message = std::move(message);
  return r;
}

ActionResult not_waited(const std::string& what, CommandResult r, int axis = -1) {
  ActionResult res;
  res.message = fmt::format("{}: {} (not waiting)", what, command_result_text(static_cast<int>(r), axis));
  res.json = {{"command", what}, {"ok", true}, {"result", std::string(homing::command_result_name(r))}};
  return res;
}

bool taken(CommandResult r) { return r == CommandResult::accepted || r == CommandResult::already_running; }

}  // namespace

HomeTargets home_targets(const std::vector<std::string>& targets) {
  HomeTargets t;
  t.all = targets.empty();
  for (const auto& w : targets) {
    if (w == "all") {
      t.all = true;
      continue;
    }
    const int a = axis_index(w);
    if (a < 0) throw std::invalid_argument(fmt::format("home: '{}' is not an axis (all, x, y, z, a, b, c)", w));
    t.axes |= homing::axis_bit(static_cast<std::size_t>(a));
  }
  return t;
}

ActionResult home(Connection& c, const HomeTargets& targets, const ActionOptions& o) {
  Session s(c, o);
  std::string what = "home all";
  std::string reg = "cmd.home_all";
  if (!targets.all) {
    what = "home";
    for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
      if (!(targets.axes & homing::axis_bit(a))) continue;
      what += fmt::format(" {}", homing::kAxisUpper[a]);
      if (s.settings.axes[a].mode == homing::HomingMode::disabled)
        return failure(fmt::format("{}: {} is disabled (axis.{}.mode = disabled), it cannot be homed", what,
                                   homing::kAxisUpper[a], homing::kAxisLetters[a]));
    }
    reg = "cmd.home_axes";
  }
  auto r = s.pulse(reg, targets.all ? 1 : targets.axes);
  if (!r) {
    // The module refuses a cmd.home_axes write it cannot start (04, 06):
    // say why, as for a refused command.
    const StatusView st = read_status(c, s.settings);
    const CommandResult why = homing::homing_refusal_of(st.interlocks);
    if (!targets.all && why != CommandResult::accepted) return s.refused(what, why, &st);
    return failure(r.error());
  }
  if (!taken(*r)) {
    if (*r == CommandResult::refused_settings_fault) {
      auto st = read_status(c, s.settings);
      return s.refused(what, *r, &st);
    }
    return s.refused(what, *r);
  }
  if (!o.wait) return not_waited(what, *r);
  auto st = s.wait_for(at_rest, true);
  if (!st) return failure(st.error());
  ActionResult last = s.finished(what, *st);
  if (last.exit_code != 0) return last;
  if (st->state != homing::MachineState::homed && targets.all) {
    last.exit_code = 1;
    last.message = fmt::format("{}: not done, the machine ended {}", what, homing::state_name(st->state));
  }
  return last;
}

ActionResult abort_motion(Connection& c, const ActionOptions& o) {
  Session s(c, o);
  auto r = s.pulse("cmd.abort");
  if (!r) return failure(r.error());
  if (!taken(*r)) return s.refused("abort", *r);
  if (!o.wait) return not_waited("abort", *r);
  auto st = s.wait_for(at_rest);
  if (!st) return failure(st.error());
  auto res = s.finished("abort", *st, false);
  if (st->alarm) res.message += "\n(reset with `homingctl reset` before homing again)";
  return res;
}

ActionResult reset_alarm(Connection& c, const ActionOptions& o) {
  Session s(c, o);
  auto r = s.pulse("cmd.reset_alarm");
  if (!r) return failure(r.error());
  if (!taken(*r)) return s.refused("reset", *r);
  StatusView st = read_status(c, s.settings);
  if (st.state == homing::MachineState::alarm || st.alarm) {
    auto res = s.finished("reset", st);
    res.exit_code = 1;
    res.message = "reset did not clear the alarm: " + res.message;
    return res;
  }
  return s.finished("reset", st);
}

ActionResult jog(Connection& c, const std::string& axis, int direction, int ms, const ActionOptions& o) {
  const int a = axis_index(axis);
  if (a < 0) throw std::invalid_argument(fmt::format("jog: '{}' is not an axis (x, y, z, a, b, c)", axis));
  Session s(c, o);
  const std::string coil = fmt::format("cmd.jog_{}.{}", direction > 0 ? "plus" : "minus",
                                       homing::kAxisLetters[static_cast<std::size_t>(a)]);
  const std::string what = fmt::format("jog {}{}", homing::kAxisUpper[static_cast<std::size_t>(a)], direction > 0 ? "+" : "-");
  // A button another client holds: pressing this one would start nothing
  // (the same one: held already; the other: both held stops the axis), and
  // releasing it would stop that client's jog. Said, and nothing written.
  for (const char* side : {"plus", "minus"}) {
    const std::string button =
        fmt::format("cmd.jog_{}.{}", side, homing::kAxisLetters[static_cast<std::size_t>(a)]);
    if (c.read(button) != 0)
      return failure(fmt::format("{}: not pressed: {} is held by another client ({}); release it there first",
                                 what, button,
                                 button == coil ? "the axis jogs with its button" : "both directions held is no jog"));
  }
  auto r = s.pulse(coil);
  if (!r) return failure(r.error());
  if (!taken(*r)) {
    (void)c.write(coil, 0);
    return s.refused(what, *r);
  }
  const auto until = Clock::now() + std::chrono::milliseconds(ms);
  while (Clock::now() < until) {
    s.beat();
    std::this_thread::sleep_for(std::min<Clock::duration>(until - Clock::now(), std::chrono::milliseconds(50)));
  }
  if (const int ex = c.write(coil, 0)) return failure(fmt::format("releasing {} refused: {}", coil, exception_sentence(ex)));
  if (!o.wait) return not_waited(what, *r);
  auto st = s.wait_for(at_rest);
  if (!st) return failure(st.error());
  return s.finished(what, *st);
}

ActionResult move(Connection& c, const std::string& axis, const std::string& target, const ActionOptions& o) {
  const int a = axis_index(axis);
  if (a < 0) throw std::invalid_argument(fmt::format("move: '{}' is not an axis (x, y, z, a, b, c)", axis));
  const auto letter = homing::kAxisLetters[static_cast<std::size_t>(a)];
  const auto& treg = register_named(fmt::format("axis.{}.target", letter));
  const registers::AxisKinds kinds = kinds_for(c, {&treg});  // the target in the axis's unit
  auto raw = parse_value(treg, target, kinds);
  if (!raw) throw std::invalid_argument(raw.error());
  Session s(c, o);
  if (const int ex = c.write(treg, *raw)) return failure(fmt::format("writing {} refused: {}", treg.name(), exception_sentence(ex)));
  const std::string what =
      fmt::format("move {} to {}", homing::kAxisUpper[static_cast<std::size_t>(a)], value_text(treg, *raw, kinds));
  auto r = s.pulse(fmt::format("cmd.move.{}", letter));
  if (!r) return failure(r.error());
  if (!taken(*r)) return s.refused(what, *r);
  if (!o.wait) return not_waited(what, *r);
  auto st = s.wait_for(at_rest);
  if (!st) return failure(st.error());
  return s.finished(what, *st);
}

ActionResult unhome(Connection& c, const std::string& axis, const ActionOptions& o) {
  const int a = axis_index(axis);
  if (a < 0) throw std::invalid_argument(fmt::format("unhome: '{}' is not an axis (x, y, z, a, b, c)", axis));
  const auto i = static_cast<std::size_t>(a);
  Session s(c, o);
  const std::string what = fmt::format("unhome {}", homing::kAxisUpper[i]);
  auto r = s.pulse(fmt::format("cmd.unhome.{}", homing::kAxisLetters[i]));
  if (!r) return failure(r.error());
  if (!taken(*r)) return s.refused(what, *r, nullptr, a);
  ActionResult res = s.finished(what, read_status(c, s.settings), /*alarm_is_failure=*/false);
  std::string partner;
  if (const int m = homing::gantry_master(s.settings, i); m >= 0) partner = homing::kAxisUpper[static_cast<std::size_t>(m)];
  if (const int sl = homing::gantry_slave(s.settings, i); sl >= 0) partner = homing::kAxisUpper[static_cast<std::size_t>(sl)];
  res.message = fmt::format("{}: done; {}{} no longer homed, nothing moved; home {} again before moving by coordinates",
                            what, homing::kAxisUpper[i], partner.empty() ? "" : " and its gantry partner " + partner,
                            partner.empty() ? "it" : "the pair");
  return res;
}

ActionResult refcheck(Connection& c, const std::string& axis, const ActionOptions& o) {
  const int a = axis_index(axis);
  if (a < 0) throw std::invalid_argument(fmt::format("refcheck: '{}' is not an axis (x, y, z, a, b, c)", axis));
  const auto i = static_cast<std::size_t>(a);
  Session s(c, o);
  const std::string what = fmt::format("refcheck {}", homing::kAxisUpper[i]);
  auto r = s.pulse(fmt::format("cmd.refcheck.{}", homing::kAxisLetters[i]));
  if (!r) return failure(r.error());
  if (!taken(*r)) return s.refused(what, *r, nullptr, a);
  if (!o.wait) return not_waited(what, *r, a);
  auto st = s.wait_for(at_rest, true);
  if (!st) return failure(st.error());
  ActionResult res = s.finished(what, *st);
  if (res.exit_code != 0) return res;
  const AxisView& x = st->axes[i];
  const auto unit = homing::axis_unit(s.settings, i);
  const double tolerance = s.settings.axes[i].refcheck_tolerance_mm;
  const bool accepted = x.trust == homing::Trust::reference_checked;
  res.json["accepted"] = accepted;
  res.json["refcheck_error"] = x.refcheck_error;
  res.json["trust"] = std::string(homing::name_of(x.trust));
  if (accepted) {
    res.message = fmt::format("{}: accepted, the switch edge lies {:+.3f} {} from where the stored position put it "
                              "(tolerance {:.3f} {}); {} is homed at {:.3f} {}",
                              what, x.refcheck_error, unit, tolerance, unit, homing::kAxisUpper[i], x.position, unit);
    return res;
  }
  res.exit_code = 1;
  res.json["ok"] = false;
  res.message = fmt::format("{}: refused, the switch edge lies {:+.3f} {} from where the stored position put it "
                            "(tolerance {:.3f} {}): the carriage moved or lost steps while the module was off; home "
                            "it with a full cycle (homingctl home {})",
                            what, x.refcheck_error, unit, tolerance, unit, homing::kAxisLetters[i]);
  return res;
}

}  // namespace homingctl

namespace homingctl {

// The figures a measurement left in axis.<a>.measured_*, in the axis's unit.
namespace {
struct Measured {
  double travel = 0, soft_limit_min = 0, soft_limit_max = 0, max_seek_travel = 0;
  std::int64_t raw_min = 0, raw_max = 0, raw_seek = 0;  // as written to the settings on --apply
};
Measured read_measured(Connection& c, std::string_view letter) {
  const auto name = [&](std::string_view what) { return fmt::format("axis.{}.measured_{}", letter, what); };
  const auto v = c.read_many({&register_named(name("travel")), &register_named(name("soft_limit_min")),
                              &register_named(name("soft_limit_max")), &register_named(name("max_seek_travel"))});
  Measured m;
  m.raw_min = v.at(name("soft_limit_min"));
  m.raw_max = v.at(name("soft_limit_max"));
  m.raw_seek = v.at(name("max_seek_travel"));
  m.travel = static_cast<double>(v.at(name("travel"))) / 1000.0;
  m.soft_limit_min = static_cast<double>(m.raw_min) / 1000.0;
  m.soft_limit_max = static_cast<double>(m.raw_max) / 1000.0;
  m.max_seek_travel = static_cast<double>(m.raw_seek) / 1000.0;
  return m;
}

// Through the settings path homingctl set takes: checked first, all or
// nothing, so the module's audit log records who wrote what.
std::expected<void, std::string> apply_measured(Connection& c, std::string_view letter, const Measured& m) {
  const RawMap wanted{{fmt::format("axis.{}.soft_limit_min", letter), m.raw_min},
                      {fmt::format("axis.{}.soft_limit_max", letter), m.raw_max},
                      {fmt::format("axis.{}.max_seek_travel", letter), m.raw_seek}};
  std::vector<const registers::Register*> regs = persisted_registers();
  for (const auto& [name, raw] : wanted) regs.push_back(&register_named(name));
  const RawMap current = c.read_many(regs);
  auto plan = plan_write(current, wanted, c.options().word_order);
  if (!plan) return std::unexpected(plan.error());
  return execute_plan(c, *plan);
}
}  // namespace

namespace {

// Which half of a measurement's needs this axis lacks, in its own register names.
std::string travel_end_missing(const homing::Settings& settings, std::size_t a) {
  const homing::AxisSettings& s = settings.axes[a];
  const auto letter = homing::kAxisLetters[a];
  if (!homing::homes_at_travel_end(s.mode))
    return fmt::format("axis.{}.mode is {}, which does not home at an end of the travel", letter, homing::mode_name(s.mode));
  std::string text = fmt::format("axis.{}.limits_fitted is 0: no limit switch tells the opposite end", letter);
  if (homing::mode_row(s.mode).runs(homing::Phase::push_to_stop))
    text += fmt::format(", and axis.{}.stall_detect is not stall_input", letter);
  return text;
}

}  // namespace

ActionResult measure(Connection& c, const std::string& axis, bool apply, const ActionOptions& o) {
  const int a = axis_index(axis);
  if (a < 0) throw std::invalid_argument(fmt::format("measure: '{}' is not an axis (x, y, z, a, b, c)", axis));
  const auto i = static_cast<std::size_t>(a);
  const auto letter = homing::kAxisLetters[i];
  Session s(c, o);
  const std::string what = fmt::format("measure {}", homing::kAxisUpper[i]);
  auto r = s.pulse(fmt::format("cmd.measure.{}", letter));
  if (!r) return failure(r.error());
  if (!taken(*r)) {
    ActionResult res = s.refused(what, *r, nullptr, a);
    if (*r == CommandResult::refused_no_travel_end) res.message += "\n  " + travel_end_missing(s.settings, i);
    return res;
  }
  if (!o.wait) return not_waited(what, *r, a);
  auto st = s.wait_for(at_rest, true);
  if (!st) return failure(st.error());
  ActionResult res = s.finished(what, *st);
  if (res.exit_code != 0) return res;
  const Measured m = read_measured(c, letter);
  if (m.travel <= 0) {
    res.exit_code = 1;
    res.json["ok"] = false;
    res.message = fmt::format("{}: no travel measured (the axis found no end, or stopped before it)", what);
    return res;
  }
  const auto unit = homing::axis_unit(s.settings, i);
  const homing::AxisSettings& now = s.settings.axes[i];
  res.json["measured_travel"] = m.travel;
  res.json["soft_limit_min"] = m.soft_limit_min;
  res.json["soft_limit_max"] = m.soft_limit_max;
  res.json["max_seek_travel"] = m.max_seek_travel;
  res.json["applied"] = false;
  res.message = fmt::format(
      "{}: usable travel {:.3f} {} from the home position\n"
      "  axis.{}.soft_limit_min = {:.3f} {} (now {:.3f})\n"
      "  axis.{}.soft_limit_max = {:.3f} {} (now {:.3f})\n"
      "  axis.{}.max_seek_travel = {:.3f} {} (now {:.3f})",
      what, m.travel, unit, letter, m.soft_limit_min, unit, now.soft_limit_min_mm, letter, m.soft_limit_max, unit,
      now.soft_limit_max_mm, letter, m.max_seek_travel, unit, now.max_seek_travel_mm);
  if (homing::travel_end(now) == homing::TravelEnd::hard_stop)
    res.message += fmt::format("\n  {} pushed into its stop and is no longer homed: home it again", homing::kAxisUpper[i]);
  if (!apply) {
    res.message += fmt::format("\n  nothing written: homingctl measure {} --apply writes these", letter);
    return res;
  }
  if (auto done = apply_measured(c, letter, m); !done) {
    res.exit_code = 1;
    res.json["ok"] = false;
    res.message += fmt::format("\n  not written, refused: {}", done.error());
    return res;
  }
  res.json["applied"] = true;
  res.message += "\n  written to the settings";
  if (!now.soft_limits_enable)
    res.message += fmt::format(" (axis.{}.soft_limits_enable is off: the soft limits act once it is on)", letter);
  return res;
}

}  // namespace homingctl
