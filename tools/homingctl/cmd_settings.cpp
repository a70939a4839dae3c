// get, set, check, export, import: the module's registers and settings by name.
#include <fmt/format.h>
#include <fnmatch.h>

#include <array>
#include <chrono>
#include <optional>
#include <variant>

#include "check.hpp"
#include "maps.hpp"
#include "homing/settings_check.hpp"
#include "cli.hpp"
#include "registers/lookup.hpp"
#include "settings_io.hpp"
#include "values.hpp"

namespace homingctl {

using registers::Register;
using registers::Table;
using registers::Unit;

namespace {

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

void print_changes(const Context& ctx, const WritePlan& plan) {
  for (const auto& ch : plan.changes)
    if (!ctx.json)
      fmt::print("{}: {} -> {}\n", ch.reg->name(), value_text(*ch.reg, ch.old_raw, plan.kinds),
                 value_text(*ch.reg, ch.new_raw, plan.kinds));
}

int get(Context& ctx, const std::vector<std::string>& names) {
  const auto regs = resolve(names);
  Connection& c = ctx.connection();
  const auto values = c.read_many(regs);
  const registers::AxisKinds kinds = kinds_for(c, regs);
  nlohmann::json j = nlohmann::json::object();
  for (const Register* r : regs) {
    const auto raw = values.at(r->name());
    if (ctx.json) j[r->name()] = value_json(*r, raw, kinds);
    else fmt::print("{} = {}\n", r->name(), value_text(*r, raw, kinds));
  }
  if (ctx.json) print_json(j);
  return kOk;
}

struct SetOptions {
  std::vector<std::string> assignments;
  bool no_check = false, dry_run = false;
};

// NAME=VALUE assignments as raw values: module settings (one planned write)
// and simulator values (written one by one).
struct Assignments {
  RawMap module;
  std::vector<std::pair<const Register*, std::int64_t>> simulator;
  registers::AxisKinds kinds = registers::default_kinds();  // the units the values were read in
};

// The assignments, or the exit code of a refusal already printed.
// Values are read in the units of the kinds the axes move with now.
std::variant<Assignments, int> parse_assignments(Context& ctx, const std::vector<std::string>& texts) {
  Assignments out;
  std::vector<std::pair<const Register*, std::string>> named;
  for (const auto& a : texts) {
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
    // set changes settings; a command or a host value written through it
    // would act (cmd.home_axes starts a cycle) while reported as a setting.
    if (r->unit == Unit::module && !r->persisted && r->key != registers::Key::security_unlock)
      throw Usage(fmt::format("{} is not a setting (a command or a value the host writes): use homingctl "
                              "home/abort/reset/jog/move",
                              r->name()));
    named.emplace_back(r, kv->second);
  }
  // A unit typed with a value is that of the kind the axis will have: this
  // command may set axis.<a>.kind or slave_of too (value names, no unit).
  std::vector<const Register*> regs;
  RawMap changing;
  for (const auto& [r, text] : named) {
    regs.push_back(r);
    if (r->type == registers::Type::enumeration && r->persisted)
      if (auto raw = parse_value(*r, text)) changing[r->name()] = *raw;
  }
  const registers::AxisKinds kinds = kinds_for(ctx.connection(), regs, changing);
  out.kinds = kinds;
  for (const auto& [r, text] : named) {
    auto raw = parse_value(*r, text, kinds);
    if (!raw) {
      fmt::print(stderr, "refused: {}; nothing was written\n", raw.error());
      return kFailed;
    }
    if (r->unit == Unit::simulator) out.simulator.emplace_back(r, *raw);
    else out.module[r->name()] = *raw;
  }
  return out;
}

int set_module_settings(Context& ctx, const RawMap& wanted, const SetOptions& o) {
  Connection& c = ctx.connection();
  std::vector<const Register*> regs = persisted_registers();
  for (const auto& [name, raw] : wanted) regs.push_back(&register_named(name));
  // Fillers of a block may be non-persisted registers of the same run.
  const RawMap current = c.read_many(regs);
  auto plan = plan_write(current, wanted, ctx.co.word_order, !o.no_check);
  if (!plan) {
    fmt::print(stderr, "refused: {}\n", plan.error());
    return kFailed;
  }
  // Printed once the module took them (a dry run: as planned): stdout never
  // records a change the module refused.
  if (!o.dry_run) {
    if (auto done = execute_plan(c, *plan); !done) {
      fmt::print(stderr, "refused: {}\n", done.error());
      return kFailed;
    }
  }
  print_changes(ctx, *plan);
  if (plan->changes.empty() && !ctx.json) fmt::print("nothing to change\n");
  return kOk;
}

// Echoed in the unit they were read in: a simulated carriage has its axis's kind.
int set_simulator_values(Context& ctx, const std::vector<std::pair<const Register*, std::int64_t>>& writes,
                         const registers::AxisKinds& kinds, const SetOptions& o) {
  Connection& c = ctx.connection();
  for (const auto& [r, raw] : writes) {
    if (o.dry_run) continue;
    if (const int ex = c.write(*r, raw)) {
      fmt::print(stderr, "refused: {} = {}: {}: {}\n", r->name(), value_text(*r, raw, kinds),
                 ex == 6 ? "exception 06: the simulated carriage cannot be placed while it moves"
                         : exception_sentence(ex),
                 refusal_reason(c, Unit::simulator));
      return kFailed;
    }
    if (!ctx.json) fmt::print("{} = {}\n", r->name(), value_text(*r, raw, kinds));
  }
  return kOk;
}

int set(Context& ctx, const SetOptions& o) {
  const auto parsed = parse_assignments(ctx, o.assignments);
  if (const int* refused = std::get_if<int>(&parsed)) return *refused;
  const Assignments& a = std::get<Assignments>(parsed);
  if (!a.module.empty())
    if (const int rc = set_module_settings(ctx, a.module, o); rc != kOk) return rc;
  if (const int rc = set_simulator_values(ctx, a.simulator, a.kinds, o); rc != kOk) return rc;
  if (ctx.json) print_json({{"ok", true}, {"dry_run", o.dry_run}});
  return kOk;
}

// The simulated trigger cams, when there is a simulator unit (none on a real machine).
std::array<std::optional<TriggerCam>, homing::kAxisCount> simulated_cams(Context& ctx) {
  std::array<std::optional<TriggerCam>, homing::kAxisCount> cams;
  if (!ctx.co.rtu.empty() || ctx.co.sim_unit <= 0) return cams;
  Connection& c = ctx.connection();
  try {
    for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
      const auto l = homing::kAxisLetters[a];
      auto v = c.read_many({&register_named(fmt::format("sim.{}.sensor_min", l)),
                            &register_named(fmt::format("sim.{}.sensor_max", l)),
                            &register_named(fmt::format("sim.{}.hysteresis", l)),
                            &register_named(fmt::format("sim.{}.limit_min", l)),
                            &register_named(fmt::format("sim.{}.limit_max", l))});
      cams[a] = TriggerCam{v.at(fmt::format("sim.{}.sensor_min", l)) / 1000.0,
                           v.at(fmt::format("sim.{}.sensor_max", l)) / 1000.0,
                           v.at(fmt::format("sim.{}.hysteresis", l)) / 1000.0,
                           v.at(fmt::format("sim.{}.limit_min", l)) / 1000.0,
                           v.at(fmt::format("sim.{}.limit_max", l)) / 1000.0};
    }
  } catch (const ModbusException&) {
    cams.fill(std::nullopt);  // no simulator unit (real machine)
  }
  return cams;
}

int check(Context& ctx) {
  const auto settings = read_settings(ctx.connection());
  const auto r = check_settings(settings, simulated_cams(ctx));
  if (ctx.json) print_json(check_json(r)); else fmt::print("{}", render_check(r));
  return r.ok() ? kOk : kFailed;
}

int export_settings(Context& ctx, const std::string& file) {
  Connection& c = ctx.connection();
  const auto values = read_settings_raw(c);
  const std::string text = settings_file_text(values, fmt::format("homingctl over {}", c.describe()), now_ms());
  if (auto w = write_file_atomically(file, text); !w) {
    fmt::print(stderr, "homingctl export: {}\n", w.error());
    return kFailed;
  }
  if (ctx.json) print_json({{"ok", true}, {"file", file}, {"settings", values.size()}});
  else fmt::print("exported {} settings to {}\n", values.size(), file);
  return kOk;
}

// The HMI tag files of this machine: from the module's settings, or from a
// settings file (no module needed).
struct MapsOptions {
  std::string dir;
  std::string from;  // a settings file; "" = the module's settings
};

int write_machine_maps(Context& ctx, const MapsOptions& o) {
  RawMap values;
  std::string source;
  if (o.from.empty()) {
    Connection& c = ctx.connection();
    values = read_settings_raw(c);
    source = fmt::format("the settings of the module at {}", c.describe());
  } else {
    auto file = read_settings_file(o.from);
    if (!file) {
      fmt::print(stderr, "homingctl maps: {}; nothing was written\n", file.error());
      return kFailed;
    }
    values = file->values;
    source = o.from;
  }
  const registers::MapUnits units = map_units_of(values, source);
  auto n = write_maps(o.dir, units);
  if (!n) {
    fmt::print(stderr, "homingctl maps: {}\n", n.error());
    return kFailed;
  }
  std::string kinds;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a)
    kinds += fmt::format("{}{} {}", a ? ", " : "", homing::kAxisUpper[a], homing::name_of(units.kinds[a]));
  if (ctx.json) print_json({{"ok", true}, {"dir", o.dir}, {"files", *n}, {"source", source}});
  else fmt::print("wrote {} map files to {} for {} ({})\n", *n, o.dir, source, kinds);
  return kOk;
}

// Where in the file the setting of a broken cross-setting rule is, with its
// value ("machine.toml:12: axis.x.max_stop_distance = 10.0: "), or the file.
std::string rule_location(const std::string& file, const SettingsFileValues& wanted, const RawMap& current) {
  RawMap after = current;
  for (const auto& [name, raw] : wanted.values) after[name] = raw;
  const auto fault = homing::new_fault(settings_of(current), settings_of(after));
  if (!fault || fault->field == homing::AxisField::none) return file + ": ";
  const std::string name = fmt::format("axis.{}.{}", homing::kAxisLetters[fault->axis], homing::field_name(fault->field));
  const auto line = wanted.lines.find(name);
  const Register* r = registers::find_register(name);
  if (line == wanted.lines.end() || !r || !after.contains(name)) return file + ": ";
  return fmt::format("{}:{}: {} = {}: ", file, line->second, name, file_value_text(*r, after.at(name)));
}

int import_settings(Context& ctx, const std::string& file, bool dry_run) {
  auto wanted = read_settings_file(file);
  if (!wanted) {
    fmt::print(stderr, "refused: {}\n", wanted.error());
    return kFailed;
  }
  Connection& c = ctx.connection();
  const auto current = read_settings_raw(c);
  auto plan = plan_write(current, wanted->values, ctx.co.word_order);
  if (!plan) {
    fmt::print(stderr, "refused: {}{}\n", rule_location(file, *wanted, current), plan.error());
    return kFailed;
  }
  if (!dry_run)
    if (auto done = execute_plan(c, *plan); !done) {
      fmt::print(stderr, "refused: {}\n", done.error());
      return kFailed;
    }
  print_changes(ctx, *plan);
  const std::size_t not_in_file = current.size() - wanted->values.size();
  if (ctx.json)
    print_json({{"ok", true}, {"dry_run", dry_run}, {"changed", plan->changes.size()}, {"not_in_file", not_in_file}});
  else
    fmt::print("{} {} settings from {} ({} requests); {} not in the file (kept)\n", dry_run ? "would change" : "changed",
               plan->changes.size(), file, plan->blocks.size(), not_in_file);
  return kOk;
}

}  // namespace

void add_settings_commands(Commands& commands, Context&) {
  auto names = std::make_shared<std::vector<std::string>>();
  commands.add("get", "read registers by name in engineering units (patterns: 'axis.x.*')",
               [names](Context& c) { return get(c, *names); })
      ->add_option("names", *names, "register names or patterns")
      ->required();

  auto set_options = std::make_shared<SetOptions>();
  auto* set_cmd = commands.add("set", "write settings NAME=VALUE (mm, mm/min, enum names) in one all-or-nothing write",
                               [set_options](Context& c) { return set(c, *set_options); });
  set_cmd->add_option("assignments", set_options->assignments,
                      "e.g. axis.x.seek_feedrate=1200 axis.x.mode=switch_reapproach")
      ->required();
  set_cmd->add_flag("--no-check", set_options->no_check, "skip the local check (the module still checks)");
  set_cmd->add_flag("--dry-run", set_options->dry_run, "show what would change, write nothing");

  commands.add("check", "what the settings imply per axis before anything moves", check);

  auto file = std::make_shared<std::string>();
  commands.add("export", "write all settings to a TOML file in engineering units and value names (the daemon's export format)",
               [file](Context& c) { return export_settings(c, *file); })
      ->add_option("file", *file, "output file")
      ->required();
  auto maps = std::make_shared<MapsOptions>();
  auto* maps_cmd = commands.add("maps", "write the HMI tag files (Kepware, Ignition, Home Assistant, CSV, JSON, Markdown) "
                                        "of this machine: each axis in the unit of its axis.<a>.kind",
                                [maps](Context& c) { return write_machine_maps(c, *maps); });
  maps_cmd->add_option("dir", maps->dir, "directory to write into")->required();
  maps_cmd->add_option("--from", maps->from, "a settings file (homingctl export) instead of the module's settings");
  auto dry_run = std::make_shared<bool>(false);
  auto* import_cmd = commands.add("import", "write the settings of a TOML file (engineering values, or raw ones of a format_version 1 file; checked first; all or nothing)",
                                  [file, dry_run](Context& c) { return import_settings(c, *file, *dry_run); });
  import_cmd->add_option("file", *file, "settings file")->required();
  import_cmd->add_flag("--dry-run", *dry_run, "show what would change, write nothing");
}

}  // namespace homingctl
