#include "config.hpp"

#include <fmt/format.h>

#include <set>
#include <toml++/toml.h>

namespace homing::gpiod {
namespace {

using Error = std::unexpected<std::string>;

struct Ctx {
  std::string origin;
  std::string default_chip;
};

std::expected<Bias, std::string> parse_bias(const std::string& text, const std::string& where) {
  if (text == "as-is") return Bias::as_is;
  if (text == "disable") return Bias::disable;
  if (text == "pull-up") return Bias::pull_up;
  if (text == "pull-down") return Bias::pull_down;
  return Error(fmt::format("{}: bias \"{}\" is not one of \"as-is\", \"pull-up\", \"pull-down\", \"disable\"",
                           where, text));
}

// A line is `23` (offset on the default chip), `"NAME"` (a line name) or
// `{ chip = "gpiochip1", line = 23, active_low = true, bias = "pull-up" }`.
std::expected<LineSpec, std::string> parse_line(const Ctx& ctx, const std::string& section, const std::string& key,
                                                const toml::node& node) {
  const std::string where = fmt::format("{}: [{}] {}", ctx.origin, section, key);
  LineSpec spec;
  spec.role = key;
  spec.chip = ctx.default_chip;
  const toml::node* line = &node;
  if (const auto* t = node.as_table()) {
    for (const auto& [k, v] : *t) {
      const std::string name(k.str());
      if (name != "chip" && name != "line" && name != "active_low" && name != "bias")
        return Error(fmt::format("{}: unknown key '{}' (known: chip, line, active_low, bias)", where, name));
    }
    if (const auto chip = (*t)["chip"]) {
      if (!chip.is_string()) return Error(where + ": chip must be a string such as \"gpiochip0\"");
      spec.chip = chip.as_string()->get();
    }
    if (const auto al = (*t)["active_low"]) {
      if (!al.is_boolean()) return Error(where + ": active_low must be true or false");
      spec.active_low = al.as_boolean()->get();
    }
    if (const auto b = (*t)["bias"]) {
      if (!b.is_string()) return Error(where + ": bias must be a string");
      auto bias = parse_bias(b.as_string()->get(), where);
      if (!bias) return Error(bias.error());
      spec.bias = *bias;
    }
    line = t->get("line");
    if (!line) return Error(where + ": missing 'line' (an offset such as 23 or a line name such as \"GPIO23\")");
  }
  if (const auto* i = line->as_integer()) {
    if (i->get() < 0 || i->get() > 1023) return Error(fmt::format("{}: line offset {} is not 0..1023", where, i->get()));
    spec.line = static_cast<unsigned>(i->get());
    if (spec.chip.empty())
      return Error(where + ": a line offset needs a chip: set chip = \"gpiochip0\" in [gpiod] or in the line");
  } else if (const auto* s = line->as_string()) {
    if (s->get().empty()) return Error(where + ": the line name is empty");
    spec.line = s->get();
  } else {
    return Error(where + ": expected a line offset (23), a line name (\"GPIO23\") or a table { chip, line, ... }");
  }
  return spec;
}

// The wiring is read before the settings: the unit of steps_per_unit is the
// axis's kind (axis.<a>.kind), mm on X, Y, Z.
std::string unit_text(std::size_t a) {
  if (!may_be_rotary(a)) return std::string(unit_of(AxisKind::linear));
  return fmt::format("deg, or mm when axis.{}.kind = linear", kAxisLetters[a]);
}

std::expected<std::int64_t, std::string> parse_int(const Ctx& ctx, const toml::node& node, const std::string& key,
                                                   std::int64_t lo, std::int64_t hi) {
  const auto* i = node.as_integer();
  if (!i || i->get() < lo || i->get() > hi)
    return Error(fmt::format("{}: [gpiod] {} must be an integer in {}..{}", ctx.origin, key, lo, hi));
  return i->get();
}

std::expected<void, std::string> parse_axis(const Ctx& ctx, std::size_t a, const toml::table& t, AxisLines& out) {
  const std::string section = fmt::format("gpiod.axes.{}", kAxisUpper[a]);
  const std::string prefix(1, kAxisUpper[a]);
  out.configured = true;
  const std::pair<const char*, std::optional<LineSpec> AxisLines::*> lines[] = {
      {"step", &AxisLines::step},       {"dir", &AxisLines::dir},
      {"enable", &AxisLines::enable},   {"push", &AxisLines::push},
      {"commutator", &AxisLines::commutator}, {"home", &AxisLines::home},
      {"index", &AxisLines::index},     {"drive_fault", &AxisLines::drive_fault},
      {"stall", &AxisLines::stall},     {"home_request", &AxisLines::home_request},
      {"home_done", &AxisLines::home_done}, {"unlock", &AxisLines::unlock}, {"unlocked", &AxisLines::unlocked},
      {"limit_min", &AxisLines::limit_min}, {"limit_max", &AxisLines::limit_max}};
  for (const auto& [k, v] : t) {
    const std::string key(k.str());
    if (key == "steps_per_unit") {
      const auto d = v.value<double>();
      if (!d || !(*d > 0) || *d > 1e6)
        return Error(fmt::format("{}: [{}] steps_per_unit must be a number > 0 (motor steps per {})", ctx.origin,
                                 section, unit_text(a)));
      out.steps_per_unit = *d;
      continue;
    }
    bool known = false;
    for (const auto& [name, member] : lines) {
      if (key != name) continue;
      auto spec = parse_line(ctx, section, key, v);
      if (!spec) return Error(spec.error());
      spec->role = prefix + "." + key;
      out.*member = *spec;
      known = true;
    }
    if (!known)
      return Error(fmt::format("{}: [{}] unknown key '{}' (known: steps_per_unit, step, dir, enable, push, "
                               "commutator, home, index, drive_fault, stall, home_request, home_done, unlock, "
                               "unlocked, limit_min, limit_max)",
                               ctx.origin, section, key));
  }
  // Neither: an axis with no output of its own (an external-commutator slave,
  // moved by its master's output); whether the settings agree is checked
  // once they are known (check_wiring).
  if (!out.step && !out.dir) {
    if (out.push || out.commutator)
      return Error(fmt::format("{}: [{}] has no step/dir output, so no '{}' line either (an external commutator "
                               "is wired on the master's axis)",
                               ctx.origin, section, out.push ? "push" : "commutator"));
    return {};
  }
  if (!out.step || !out.dir)
    return Error(fmt::format("{}: [{}] needs both 'step' and 'dir' lines (the axis drives a step/dir motor)",
                             ctx.origin, section));
  if (out.steps_per_unit <= 0)
    return Error(fmt::format("{}: [{}] needs steps_per_unit (motor steps per {}, e.g. 400)", ctx.origin, section,
                             unit_text(a)));
  return {};
}

// Two signals on one line would fight each other (or one would never see
// its edges): refuse before touching the hardware.
std::expected<void, std::string> check_unique(const BackendConfig& c, const std::string& origin) {
  std::vector<const LineSpec*> all;
  for (const auto* o : {&c.estop, &c.drive_fault, &c.start_button, &c.homing_permit, &c.homing_done_lamp})
    if (*o) all.push_back(&**o);
  for (const AxisLines& a : c.axes)
    for (const auto* o : {&a.step, &a.dir, &a.enable, &a.push, &a.commutator, &a.home, &a.index, &a.drive_fault,
                          &a.stall, &a.home_request, &a.home_done, &a.unlock, &a.unlocked,
                          &a.limit_min, &a.limit_max})
      if (*o) all.push_back(&**o);
  for (std::size_t i = 0; i < all.size(); ++i)
    for (std::size_t j = i + 1; j < all.size(); ++j)
      if (all[i]->chip == all[j]->chip && all[i]->line == all[j]->line)
        return Error(fmt::format("{}: {} and {} are on the same line; each signal needs its own", origin,
                                 describe(*all[i]), describe(*all[j])));
  return {};
}

}  // namespace

std::expected<BackendConfig, std::string> parse_config(const toml::table& root, const std::string& origin) {
  const toml::table* g = root["gpiod"].as_table();
  if (!g)
    return Error(origin + ": no [gpiod] table; --backend gpiod needs one naming the lines (see homing/gpiod/README.md)");
  BackendConfig c;
  Ctx ctx{origin, ""};
  if (const auto chip = (*g)["chip"]) {
    if (!chip.is_string()) return Error(origin + ": [gpiod] chip must be a string such as \"gpiochip0\"");
    ctx.default_chip = chip.as_string()->get();
  }
  const std::pair<const char*, std::optional<LineSpec> BackendConfig::*> lines[] = {
      {"estop", &BackendConfig::estop},
      {"drive_fault", &BackendConfig::drive_fault},
      {"start_button", &BackendConfig::start_button},
      {"homing_permit", &BackendConfig::homing_permit},
      {"homing_done_lamp", &BackendConfig::homing_done_lamp}};
  const std::pair<const char*, std::int64_t BackendConfig::*> ints[] = {
      {"tick_us", &BackendConfig::tick_us},
      {"dir_setup_us", &BackendConfig::dir_setup_us},
      {"input_debounce_ms", &BackendConfig::input_debounce_ms},
      {"playback_delay_us", &BackendConfig::playback_delay_us}};
  bool any_axis = false;
  for (const auto& [k, v] : *g) {
    const std::string key(k.str());
    if (key == "chip") continue;
    if (key == "axes") {
      const auto* axes = v.as_table();
      if (!axes) return Error(origin + ": [gpiod] axes must be a table: [gpiod.axes.X]");
      for (const auto& [ak, av] : *axes) {
        const std::string name(ak.str());
        std::size_t a = kAxisCount;
        for (std::size_t i = 0; i < kAxisCount; ++i)
          if (name.size() == 1 && (name[0] == kAxisUpper[i] || name[0] == kAxisLetters[i][0])) a = i;
        if (a == kAxisCount || !av.is_table())
          return Error(fmt::format("{}: [gpiod.axes.{}] is not an axis (X Y Z A B C)", origin, name));
        if (auto r = parse_axis(ctx, a, *av.as_table(), c.axes[a]); !r) return Error(r.error());
        any_axis = true;
      }
      continue;
    }
    if (key == "rt_priority") {
      auto p = parse_int(ctx, v, key, 0, 99);
      if (!p) return Error(p.error());
      c.rt_priority = static_cast<int>(*p);
      continue;
    }
    bool known = false;
    for (const auto& [name, member] : ints) {
      if (key != name) continue;
      auto value = parse_int(ctx, v, key, key == std::string("tick_us") ? 2 : 0, 1'000'000);
      if (!value) return Error(value.error());
      c.*member = *value;
      known = true;
    }
    for (const auto& [name, member] : lines) {
      if (key != name) continue;
      auto spec = parse_line(ctx, "gpiod", key, v);
      if (!spec) return Error(spec.error());
      c.*member = *spec;
      known = true;
    }
    if (!known)
      return Error(fmt::format("{}: [gpiod] unknown key '{}' (known: chip, tick_us, dir_setup_us, input_debounce_ms, "
                               "playback_delay_us, rt_priority, estop, drive_fault, start_button, homing_permit, "
                               "homing_done_lamp, [gpiod.axes.X])",
                               origin, key));
  }
  if (!any_axis) return Error(origin + ": [gpiod] configures no axis; add at least [gpiod.axes.X] with step, dir, steps_per_unit");
  if (auto r = check_unique(c, origin); !r) return Error(r.error());
  return c;
}

namespace {
bool has_line(const AxisLines& lines, homing::Signal signal) {
  switch (signal) {
    case homing::Signal::step_output: return lines.has_output();
    case homing::Signal::home_sensor: return lines.home.has_value();
    case homing::Signal::index: return lines.index.has_value();
    case homing::Signal::push_output: return lines.push.has_value();
    case homing::Signal::absolute_encoder: return false;  // no GPIO line carries it
    case homing::Signal::stall: return lines.stall.has_value();
    case homing::Signal::drive_request: return lines.home_request.has_value();
    case homing::Signal::drive_done: return lines.home_done.has_value();
    case homing::Signal::limit_min: return lines.limit_min.has_value();
    case homing::Signal::limit_max: return lines.limit_max.has_value();
  }
  return false;
}
}  // namespace

std::optional<std::string> check_wiring(const BackendConfig& config, const homing::Settings& settings) {
  using homing::HomingMode;
  auto letter = [](std::size_t a) { return std::string(1, kAxisUpper[a]); };
  auto lower = [](std::size_t a) { return std::string(kAxisLetters[a]); };
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const homing::AxisSettings& s = settings.axes[a];
    const AxisLines& lines = config.axes[a];
    // Without its lines the indexer could never be unlocked (or seen locked).
    if (s.indexer_lock && (!lines.unlock || !lines.unlocked))
      return fmt::format("axis.{0}.indexer_lock is on but [gpiod.axes.{1}] has no '{2}' line (the {3}); wire "
                         "both 'unlock' (output) and 'unlocked' (input) or set axis.{0}.indexer_lock = 0",
                         lower(a), letter(a), lines.unlock ? "unlocked" : "unlock",
                         lines.unlock ? "input that reports the indexer unlocked" : "output that unlocks the indexer");
    // Without both lines a limit switch could never trip: the axis would run into its stop.
    if (s.limits_fitted && (!lines.limit_min || !lines.limit_max))
      return fmt::format("axis.{0}.limits_fitted is on but [gpiod.axes.{1}] has no '{2}' line (the end-of-travel "
                         "limit switch at the {3} end); wire both 'limit_min' and 'limit_max' or set "
                         "axis.{0}.limits_fitted = 0",
                         lower(a), letter(a), lines.limit_min ? "limit_max" : "limit_min",
                         lines.limit_min ? "positive" : "negative");
    if (s.mode == HomingMode::disabled) continue;
    const int m = homing::master_of(s);
    const bool commutator_slave = s.slave_mode == homing::SlaveMode::external_commutator && m >= 0 &&
                                  m < static_cast<int>(kAxisCount) && m != static_cast<int>(a);
    if (commutator_slave) {
      const auto mi = static_cast<std::size_t>(m);
      const AxisLines& master = config.axes[mi];
      if (!master.has_output())
        return fmt::format("{0} is an external-commutator slave of {1} (axis.{2}.slave_of, slave_mode), but "
                           "[gpiod.axes.{1}] has no step/dir output to drive both motors",
                           letter(a), letter(mi), lower(a));
      if (!master.commutator)
        return fmt::format("{0} is an external-commutator slave of {1} (axis.{2}.slave_of, slave_mode), but "
                           "[gpiod.axes.{1}] has no 'commutator' output line to switch {1}'s output to {0}",
                           letter(a), letter(mi), lower(a));
      continue;  // moved by the master's output; its switch is read on the master's home line
    }
    // No line carries an encoder's position: such an axis could only ever end
    // in encoder_fault, so it is refused here, by name, before anything moves.
    if (homing::needs_signal(s, homing::Signal::absolute_encoder)) {
      if (s.mode == HomingMode::hard_stop)
        return fmt::format("axis.{0}.stall_detect is 1 (following error: the encoder tells the stop) but the GPIO "
                           "backend reads no encoder; wire the drive's stall output as 'stall' in [gpiod.axes.{1}] "
                           "and set axis.{0}.stall_detect = 0",
                           lower(a), letter(a));
      return fmt::format("axis.{0}.mode {1} reads an absolute encoder but the GPIO backend reads no encoder; give "
                         "{2} a method without one (manual 1, a switch 2-4, 7, 8, 11, a hard stop 9 on the stall "
                         "input, its drive 10)",
                         lower(a), static_cast<int>(s.mode), letter(a));
    }
    // Every line the axis's method needs (modes.hpp, with the stop detection
    // its stall_detect chooses), in the table's order.
    for (const homing::SignalInfo& sig : homing::kSignalInfo) {
      if (!sig.gpio_line_required || !homing::needs_signal(s, sig.signal) || has_line(lines, sig.signal)) continue;
      if (sig.signal == homing::Signal::step_output)
        return fmt::format("axis.{0}.mode is {1} (the axis can move) but [gpiod.axes.{2}] has no step/dir output; "
                           "wire {2} or set axis.{0}.mode = 0 (disabled)",
                           lower(a), static_cast<int>(s.mode), letter(a));
      return fmt::format("axis.{0}.mode {1} {2} but [gpiod.axes.{3}] has no '{4}' line", lower(a),
                         static_cast<int>(s.mode), sig.use, letter(a), sig.name);
    }
  }
  return std::nullopt;
}

std::expected<BackendConfig, std::string> load_config(const std::string& path) {
  if (path.empty())
    return Error("it needs --config FILE with a [gpiod] table naming the lines (see homing/gpiod/README.md)");
  try {
    return parse_config(toml::parse_file(path), path);
  } catch (const toml::parse_error& e) {
    return Error(fmt::format("{}: line {}: {}", path, e.source().begin.line, e.description()));
  }
}

}  // namespace homing::gpiod
