// homingctl: the operator's command-line client of homingd (Modbus TCP or RTU).
// It knows the register table by name and unit. Exit codes: 0 ok, 1 the
// operation failed (alarm, refused command or write: the reason is printed),
// 2 usage error, 3 cannot connect / no answer.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fnmatch.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <thread>

#include "actions.hpp"
#include "check.hpp"
#include "connection.hpp"
#include "history.hpp"
#include "local_daemon.hpp"
#include "registers/lookup.hpp"
#include "settings_io.hpp"
#include "status_view.hpp"
#include "trace_svg.hpp"
#include "values.hpp"

using namespace homingctl;
using registers::Register;
using registers::Table;
using registers::Unit;

namespace {

constexpr int kOk = 0, kFailed = 1, kUsage = 2, kNoLink = 3;

struct Usage : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

void print_json(const nlohmann::json& j) { fmt::print("{}\n", j.dump(2)); }

std::int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// Names or glob patterns ("axis.x.*") -> registers.
std::vector<const Register*> resolve(const std::vector<std::string>& names) {
  std::vector<const Register*> out;
  for (const auto& n : names) {
    if (n.find_first_of("*?[") == std::string::npos) {
      const Register* r = registers::find_register(n);
      if (!r) throw Usage(fmt::format("no register named '{}' (see hmi_maps/registers.md; patterns like 'axis.x.*' work)", n));
      out.push_back(r);
      continue;
    }
    std::size_t matched = 0;
    for (const Register& r : registers::all_registers()) {
      if (r.table == Table::coil && r.access == registers::Access::w) continue;  // commands read 0
      if (fnmatch(n.c_str(), r.name().c_str(), 0) == 0) {
        out.push_back(&r);
        ++matched;
      }
    }
    if (!matched) throw Usage(fmt::format("no register matches '{}'", n));
  }
  return out;
}

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"homingctl: status, commands, settings and traces of the homing module over Modbus.\n"
               "Exit codes: 0 ok, 1 operation failed (reason printed), 2 usage error, 3 cannot connect / no answer."};
  app.fallthrough();
  app.require_subcommand(1);
  ConnectionOptions co;
  std::string word_order = "high-first";
  std::string parity = "E";
  bool json = false;
  app.add_option("--tcp", co.tcp, "Modbus TCP address HOST:PORT (default: the local homingd's, from --daemon-config, else this)")
      ->capture_default_str();
  std::string daemon_config;
  app.add_option("--daemon-config", daemon_config,
                 "homingd config file whose tcp, unit, sim_unit, word_order and db are the defaults here "
                 "(default: $HOMINGD_CONFIG, else /etc/homingd/homingd.toml when it exists)");
  app.add_option("--rtu", co.rtu, "Modbus RTU serial device (instead of TCP)");
  app.add_option("--baud", co.baud, "RTU baud rate")->capture_default_str();
  app.add_option("--parity", parity, "RTU parity N|E|O")->check(CLI::IsMember({"N", "E", "O"}))->capture_default_str();
  app.add_option("--stop-bits", co.stop_bits, "RTU stop bits")->check(CLI::IsMember({1, 2}))->capture_default_str();
  app.add_option("--unit", co.unit, "module unit id")->check(CLI::Range(0, 247))->capture_default_str();
  app.add_option("--sim-unit", co.sim_unit, "simulator unit id (0 = none)")->check(CLI::Range(0, 255))->capture_default_str();
  app.add_option("--word-order", word_order, "word order of 32-bit values (as homingd --word-order)")
      ->check(CLI::IsMember({"high-first", "low-first"}))
      ->capture_default_str();
  app.add_option("--timeout-ms", co.timeout_ms, "response timeout per request")->check(CLI::Range(10, 60000))->capture_default_str();
  app.add_flag("--json", json, "machine-readable output (read commands)");

  ActionOptions ao;
  bool no_wait = false;
  double timeout_s = 300;
  auto add_wait = [&](CLI::App* sc) {
    sc->add_flag("--no-wait", no_wait, "return once the module took the command");
    sc->add_option("--timeout-s", timeout_s, "give up waiting after this long")->capture_default_str();
  };

  auto* status = app.add_subcommand("status", "one table: every axis (mode, phase, position, homed, sensor, alarm), "
                                              "the machine state and what blocks motion");
  auto* watch = app.add_subcommand("watch", "status refreshed live with progress bars during homing; exits when a "
                                            "homing cycle ends (0 homed, 1 alarm)");
  int interval_ms = 0;
  double watch_timeout_s = 0;
  watch->add_option("--interval-ms", interval_ms, "refresh period (default 250 ms on TCP, 1000 ms on RTU)");
  watch->add_option("--timeout-s", watch_timeout_s, "stop after this long (0 = until the cycle ends or Ctrl-C)");

  std::vector<std::string> home_targets;
  auto* home = app.add_subcommand("home", "home all axes (default) or the named ones, and wait for the result");
  home->add_option("axes", home_targets, "all | x y z a b c");
  add_wait(home);
  auto* abort_cmd = app.add_subcommand("abort", "stop every motion (a running homing latches 'aborted')");
  add_wait(abort_cmd);
  auto* reset = app.add_subcommand("reset", "clear latched alarms once their cause is gone");
  std::string jog_axis, jog_dir;
  int jog_ms = 500;
  auto* jog_cmd = app.add_subcommand("jog", "jog an axis for a while: jog x + --ms 500");
  jog_cmd->add_option("axis", jog_axis, "x y z a b c")->required();
  jog_cmd->add_option("direction", jog_dir, "+ or -")->required()->check(CLI::IsMember({"+", "-", "plus", "minus"}));
  jog_cmd->add_option("--ms", jog_ms, "how long the jog coil is held")->check(CLI::Range(1, 600000))->capture_default_str();
  add_wait(jog_cmd);
  std::string move_axis, move_target;
  auto* move_cmd = app.add_subcommand("move", "move an axis to a position: move x 12.5 (mm or deg)");
  move_cmd->add_option("axis", move_axis, "x y z a b c")->required();
  move_cmd->add_option("target", move_target, "target position in the axis unit")->required();
  add_wait(move_cmd);

  std::vector<std::string> get_names;
  auto* get = app.add_subcommand("get", "read registers by name in engineering units (patterns: 'axis.x.*')");
  get->add_option("names", get_names, "register names or patterns")->required();
  std::vector<std::string> assignments;
  bool no_check = false, dry_run = false;
  auto* set = app.add_subcommand("set", "write settings NAME=VALUE (mm, mm/min, enum names) in one all-or-nothing write");
  set->add_option("assignments", assignments, "e.g. axis.x.seek_feedrate=1200 axis.x.mode=switch_reapproach")->required();
  set->add_flag("--no-check", no_check, "skip the local check (the module still checks)");
  set->add_flag("--dry-run", dry_run, "show what would change, write nothing");

  auto* check = app.add_subcommand("check", "what the settings imply per axis before anything moves");
  std::string file;
  auto* exp = app.add_subcommand("export", "write all settings to a TOML file (the daemon's export format)");
  exp->add_option("file", file, "output file")->required();
  auto* imp = app.add_subcommand("import", "write the settings of a TOML file (checked first; all or nothing)");
  imp->add_option("file", file, "settings file")->required();
  imp->add_flag("--dry-run", dry_run, "show what would change, write nothing");

  std::string db = "homingd.db";
  std::size_t n_runs = 20, n_changes = 20;
  auto* history = app.add_subcommand("history", "recent homing runs and settings changes (reads the daemon's database "
                                                "file read-only: not served over Modbus)");
  history->add_option("--db", db, "the daemon's --db file")->capture_default_str();
  history->add_option("-n,--runs", n_runs, "homing runs shown")->capture_default_str();
  history->add_option("--changes", n_changes, "settings changes shown")->capture_default_str();

  std::string trace_axis, svg_file, csv_file;
  auto* trace = app.add_subcommand("trace", "the last homing cycle of an axis (FC 20): summary, --svg FILE, --csv FILE|-");
  trace->add_option("axis", trace_axis, "x y z a b c")->required();
  trace->add_option("--svg", svg_file, "draw position, velocity and sensor against time");
  trace->add_option("--csv", csv_file, "the samples as CSV ('-' = stdout)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    (void)app.exit(e);
    return kUsage;
  }
  co.parity = parity[0];
  co.word_order = word_order == "low-first" ? registers::WordOrder::low_first : registers::WordOrder::high_first;
  const auto daemon_choice = choose_daemon_config(daemon_config);
  if (auto local = read_local_daemon(daemon_choice); !local) {
    fmt::print(stderr, "homingctl: {}{}\n", local.error(), daemon_choice.named ? "" : " (ignored)");
    if (daemon_choice.named) return kUsage;
  } else if (*local) {
    const GivenOptions given{app.get_option("--tcp")->count() > 0 || !co.rtu.empty(), app.get_option("--unit")->count() > 0,
                             app.get_option("--sim-unit")->count() > 0, app.get_option("--word-order")->count() > 0,
                             history->get_option("--db")->count() > 0};
    apply_local_daemon(**local, given, co, db);
  }
  ao.wait = !no_wait;
  ao.timeout_s = timeout_s;
  ao.poll_s = co.rtu.empty() ? 0.05 : 0.3;

  try {
    if (*history) {
      auto h = read_history(db, n_runs, n_changes);
      if (!h) {
        fmt::print(stderr, "homingctl history: {}\n", h.error());
        return kFailed;
      }
      if (json) print_json(h->json); else fmt::print("{}", h->text);
      return kOk;
    }
    // Everything else talks to the module.
    std::unique_ptr<Connection> conn;
    auto connection = [&]() -> Connection& {
      if (!conn) conn = std::make_unique<Connection>(co);
      return *conn;
    };
    auto report = [&](const ActionResult& r) {
      if (json) print_json(r.json);
      else if (r.exit_code == 0) fmt::print("{}\n", r.message);
      else fmt::print(stderr, "{}\n", r.message);
      return r.exit_code;
    };

    if (*status) {
      Connection& c = connection();
      const auto settings = read_settings(c);
      const auto s = read_status(c, settings);
      if (json) print_json(status_json(s, settings)); else fmt::print("{}", render_status(s, settings, true));
      return kOk;
    }
    if (*watch) {
      Connection& c = connection();
      std::signal(SIGINT, on_signal);
      std::signal(SIGTERM, on_signal);
      const int period = interval_ms > 0 ? interval_ms : (co.rtu.empty() ? 250 : 1000);
      const bool tty = ::isatty(STDOUT_FILENO) && !json;
      auto settings = read_settings(c);
      const auto start = std::chrono::steady_clock::now();
      bool seen_cycle = false;
      std::string last_frame;
      for (;;) {
        const auto s = read_status(c, settings);
        if (s.homing && !seen_cycle) {
          seen_cycle = true;
          settings = read_settings(c);  // cannot change during the cycle
        }
        const bool ended = seen_cycle && !s.homing && s.state != homing::MachineState::homing;
        if (json) {
          auto j = status_json(s, settings);
          j["cycle_ended"] = ended;
          fmt::print("{}\n", j.dump());
        } else {
          std::string frame = render_status(s, settings, true);
          if (tty) fmt::print("\033[H\033[2J{}", frame);
          else if (frame != last_frame) fmt::print("{}\n", frame);
          last_frame = frame;
        }
        std::fflush(stdout);
        if (ended) {
          std::vector<std::string> alarms;
          for (std::size_t a = 0; a < homing::kAxisCount; ++a)
            if (s.axes[a].alarm != homing::AlarmCode::none) alarms.push_back(alarm_text(a, s.axes[a], settings));
          if (s.state == homing::MachineState::homed && alarms.empty()) {
            if (!json) fmt::print("homing cycle ended: homed\n");
            return kOk;
          }
          if (!json) fmt::print(stderr, "homing cycle ended: {}{}{}\n", homing::state_name(s.state),
                                alarms.empty() ? "" : "\n  ", fmt::join(alarms, "\n  "));
          return kFailed;
        }
        if (g_stop) return kOk;
        if (watch_timeout_s > 0 &&
            std::chrono::steady_clock::now() - start > std::chrono::duration<double>(watch_timeout_s))
          return seen_cycle ? kFailed : kOk;
        std::this_thread::sleep_for(std::chrono::milliseconds(period));
      }
    }
    if (*home) return report(homingctl::home(connection(), home_targets, ao));
    if (*abort_cmd) return report(abort_motion(connection(), ao));
    if (*reset) return report(reset_alarm(connection(), ao));
    if (*jog_cmd) return report(homingctl::jog(connection(), jog_axis, (jog_dir == "+" || jog_dir == "plus") ? 1 : -1, jog_ms, ao));
    if (*move_cmd) return report(homingctl::move(connection(), move_axis, move_target, ao));

    if (*get) {
      const auto regs = resolve(get_names);
      Connection& c = connection();
      const auto values = c.read_many(regs);
      nlohmann::json j = nlohmann::json::object();
      for (const Register* r : regs) {
        const auto raw = values.at(r->name());
        if (json) j[r->name()] = value_json(*r, raw);
        else fmt::print("{} = {}\n", r->name(), value_text(*r, raw));
      }
      if (json) print_json(j);
      return kOk;
    }
    if (*set) {
      RawMap module_wanted;
      std::vector<std::pair<const Register*, std::int64_t>> sim_writes;
      for (const auto& a : assignments) {
        auto kv = split_assignment(a);
        if (!kv) throw Usage(kv.error());
        const Register* r = registers::find_register(kv->first);
        if (!r) throw Usage(fmt::format("no register named '{}' (see hmi_maps/registers.md)", kv->first));
        if (!r->writable()) {
          fmt::print(stderr, "{} is read-only (status): it cannot be set\n", r->name());
          return kFailed;
        }
        if (r->unit == Unit::module && r->table == Table::coil)
          throw Usage(fmt::format("{} is a command: use homingctl home/abort/reset/jog/move", r->name()));
        auto raw = parse_value(*r, kv->second);
        if (!raw) {
          fmt::print(stderr, "refused: {}; nothing was written\n", raw.error());
          return kFailed;
        }
        if (r->unit == Unit::simulator) sim_writes.emplace_back(r, *raw);
        else module_wanted[r->name()] = *raw;
      }
      Connection& c = connection();
      if (!module_wanted.empty()) {
        std::vector<const Register*> regs = persisted_registers();
        for (const auto& [name, raw] : module_wanted) regs.push_back(&register_named(name));
        // Fillers of a block may be non-persisted registers of the same run.
        const RawMap current = c.read_many(regs);
        auto plan = plan_write(current, module_wanted, co.word_order, !no_check);
        if (!plan) {
          fmt::print(stderr, "refused: {}\n", plan.error());
          return kFailed;
        }
        for (const auto& ch : plan->changes)
          if (!json) fmt::print("{}: {} -> {}\n", ch.reg->name(), value_text(*ch.reg, ch.old_raw), value_text(*ch.reg, ch.new_raw));
        if (plan->changes.empty() && !json) fmt::print("nothing to change\n");
        if (!dry_run) {
          if (auto done = execute_plan(c, *plan); !done) {
            fmt::print(stderr, "refused: {}\n", done.error());
            return kFailed;
          }
        }
      }
      for (const auto& [r, raw] : sim_writes) {
        if (dry_run) continue;
        if (const int ex = c.write(*r, raw)) {
          fmt::print(stderr, "refused: {} = {}: {}\n", r->name(), value_text(*r, raw),
                     ex == 6 ? "exception 06: the simulated carriage cannot be placed while it moves"
                             : exception_sentence(ex));
          return kFailed;
        }
        if (!json) fmt::print("{} = {}\n", r->name(), value_text(*r, raw));
      }
      if (json) print_json({{"ok", true}, {"dry_run", dry_run}});
      return kOk;
    }
    if (*check) {
      Connection& c = connection();
      const auto settings = read_settings(c);
      std::array<std::optional<TriggerCam>, homing::kAxisCount> cams;
      if (co.rtu.empty() && co.sim_unit > 0) {
        try {
          for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
            const auto l = homing::kAxisLetters[a];
            auto v = c.read_many({&register_named(fmt::format("sim.{}.sensor_min", l)),
                                  &register_named(fmt::format("sim.{}.sensor_max", l)),
                                  &register_named(fmt::format("sim.{}.hysteresis", l))});
            cams[a] = TriggerCam{v.at(fmt::format("sim.{}.sensor_min", l)) / 1000.0,
                                 v.at(fmt::format("sim.{}.sensor_max", l)) / 1000.0,
                                 v.at(fmt::format("sim.{}.hysteresis", l)) / 1000.0};
          }
        } catch (const ModbusException&) {
          cams.fill(std::nullopt);  // no simulator unit (real machine)
        }
      }
      const auto r = check_settings(settings, cams);
      if (json) print_json(check_json(r)); else fmt::print("{}", render_check(r));
      return r.ok() ? kOk : kFailed;
    }
    if (*exp) {
      Connection& c = connection();
      const auto values = read_settings_raw(c);
      const std::string text = settings_file_text(values, fmt::format("homingctl over {}", c.describe()), now_ms());
      if (auto w = write_file_atomically(file, text); !w) {
        fmt::print(stderr, "homingctl export: {}\n", w.error());
        return kFailed;
      }
      if (json) print_json({{"ok", true}, {"file", file}, {"settings", values.size()}});
      else fmt::print("exported {} settings to {}\n", values.size(), file);
      return kOk;
    }
    if (*imp) {
      auto wanted = read_settings_file(file);
      if (!wanted) {
        fmt::print(stderr, "refused: {}\n", wanted.error());
        return kFailed;
      }
      Connection& c = connection();
      const auto current = read_settings_raw(c);
      auto plan = plan_write(current, *wanted, co.word_order);
      if (!plan) {
        fmt::print(stderr, "refused: {}: {}\n", file, plan.error());
        return kFailed;
      }
      for (const auto& ch : plan->changes)
        if (!json) fmt::print("{}: {} -> {}\n", ch.reg->name(), value_text(*ch.reg, ch.old_raw), value_text(*ch.reg, ch.new_raw));
      if (!dry_run)
        if (auto done = execute_plan(c, *plan); !done) {
          fmt::print(stderr, "refused: {}\n", done.error());
          return kFailed;
        }
      const std::size_t not_in_file = current.size() - wanted->size();
      if (json)
        print_json({{"ok", true}, {"dry_run", dry_run}, {"changed", plan->changes.size()}, {"not_in_file", not_in_file}});
      else
        fmt::print("{} {} settings from {} ({} requests); {} not in the file (kept)\n", dry_run ? "would change" : "changed",
                   plan->changes.size(), file, plan->blocks.size(), not_in_file);
      return kOk;
    }
    if (*trace) {
      const int a = axis_index(trace_axis);
      if (a < 0) throw Usage(fmt::format("trace: '{}' is not an axis (x, y, z, a, b, c)", trace_axis));
      Connection& c = connection();
      Trace t;
      try {
        t = read_trace(c, static_cast<std::size_t>(a));
      } catch (const LinkError& e) {
        if (!c.is_rtu()) throw;
        throw LinkError(fmt::format("{}\n(homingd serves the traces (function 20) over Modbus TCP only: its RTU "
                                    "transport frames requests with libmodbus, which cannot receive function 20; "
                                    "use --tcp)", e.what()));
      }
      if (t.samples.empty()) {
        fmt::print(stderr, "no trace for {}: the axis has not taken part in a homing cycle since homingd started\n",
                   homing::kAxisUpper[static_cast<std::size_t>(a)]);
        return kFailed;
      }
      std::string alarm;
      if (t.alarm != homing::AlarmCode::none) {
        AxisView v;
        v.alarm = t.alarm;
        v.alarm_phase = t.alarm_phase;
        alarm = alarm_text(static_cast<std::size_t>(a), v, read_settings(c));
      }
      if (!svg_file.empty())
        if (auto w = write_file_atomically(svg_file, trace_svg(t, alarm)); !w) {
          fmt::print(stderr, "homingctl trace: {}\n", w.error());
          return kFailed;
        }
      if (!csv_file.empty()) {
        if (csv_file == "-") fmt::print("{}", trace_csv(t));
        else if (auto w = write_file_atomically(csv_file, trace_csv(t)); !w) {
          fmt::print(stderr, "homingctl trace: {}\n", w.error());
          return kFailed;
        }
      }
      if (json) {
        auto j = trace_json(t);
        if (!alarm.empty()) j["alarm"]["text"] = alarm;
        print_json(j);
      } else if (csv_file != "-") {
        fmt::print("{}: {} samples every {:g} ms over {:.3f} s", homing::kAxisUpper[static_cast<std::size_t>(a)],
                   t.samples.size(), t.interval_ms, t.duration_ms / 1000.0);
        if (t.edge_time_ms) fmt::print(", reference edge at {} ms ({:.3f} {})", *t.edge_time_ms, t.edge_position_mm,
                                       homing::axis_unit(static_cast<std::size_t>(a)));
        fmt::print("{}\n", alarm.empty() ? "" : "\n  alarm: " + alarm);
        if (!svg_file.empty()) fmt::print("drawn to {}\n", svg_file);
      }
      return kOk;
    }
  } catch (const Usage& e) {
    fmt::print(stderr, "homingctl: {}\n", e.what());
    return kUsage;
  } catch (const std::invalid_argument& e) {
    fmt::print(stderr, "homingctl: {}\n", e.what());
    return kUsage;
  } catch (const LinkError& e) {
    fmt::print(stderr, "homingctl: {}\n", e.what());
    return kNoLink;
  } catch (const ModbusException& e) {
    fmt::print(stderr, "homingctl: {}\n", e.what());
    return kFailed;
  } catch (const std::exception& e) {
    fmt::print(stderr, "homingctl: {}\n", e.what());
    return kFailed;
  }
  return kOk;
}
