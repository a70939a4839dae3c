#include "settings_io.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "homing/settings_check.hpp"
#include "persistence/settings_file.hpp"
#include "registers/defaults.hpp"
#include "registers/lookup.hpp"
#include "registers/settings_file_values.hpp"
#include "registers/validate.hpp"
#include "values.hpp"

namespace homingctl {

using registers::Register;
using registers::Table;
using registers::Unit;

const std::vector<const Register*>& persisted_registers() {
  static const std::vector<const Register*> regs = [] {
    std::vector<const Register*> v;
    for (const Register& r : registers::registers_of(Unit::module))
      if (r.table == Table::holding_register && r.persisted) v.push_back(&r);
    return v;
  }();
  return regs;
}

RawMap read_settings_raw(Connection& c) { return c.read_many(persisted_registers()); }

homing::Settings settings_of(const RawMap& raw) { return registers::settings_from_raw(raw).settings; }

homing::Settings read_settings(Connection& c) { return settings_of(read_settings_raw(c)); }

registers::AxisKinds kinds_for(Connection& c, const std::vector<const registers::Register*>& regs,
                               const RawMap& changing) {
  const bool depends = std::any_of(regs.begin(), regs.end(), [](const Register* r) {
    return r->per_axis() && homing::may_be_rotary(static_cast<std::size_t>(r->axis)) &&
           r->unit_text(registers::AxisKinds{}) != r->unit_text(registers::default_kinds());
  });
  if (!depends) return registers::default_kinds();
  RawMap values = read_settings_raw(c);
  for (const auto& [name, raw] : changing)
    if (values.contains(name)) values[name] = raw;
  return registers::kinds_of(settings_of(values));
}

namespace {

// Runs of holding registers without gaps: one write request can cover a run.
struct Run {
  std::uint16_t start = 0;
  std::uint32_t end = 0;
};
std::vector<Run> holding_runs() {
  std::vector<Run> runs;
  for (const Register& r : registers::registers_of(Unit::module)) {
    if (r.table != Table::holding_register) continue;
    if (!runs.empty() && runs.back().end == r.address)
      runs.back().end = r.end();
    else
      runs.push_back({r.address, r.end()});
  }
  return runs;
}

void apply_raw(homing::Settings& s, registers::HostRegisters& h, const Register& r, std::int64_t raw) {
  if (r.persisted)
    registers::set_setting_raw(s, r, raw);
  else
    registers::set_host_raw(h, r, raw);
}

// What the module holds before the write: its settings and host registers.
struct ModuleState {
  homing::Settings settings;
  registers::HostRegisters host;
};

ModuleState state_of(const RawMap& current) {
  ModuleState s{settings_of(current), registers::default_host_registers()};
  for (const auto& [name, raw] : current) {
    const Register* r = registers::find_register(name);
    if (r && r->unit == Unit::module && r->table == Table::holding_register && !r->persisted)
      registers::set_host_raw(s.host, *r, raw);
  }
  return s;
}

// The values that change, each a setting in its range; `after` gets them.
std::expected<std::vector<PlannedChange>, std::string> changes_of(const RawMap& current, const RawMap& wanted,
                                                                  bool check, ModuleState& after) {
  const registers::AxisKinds kinds = registers::kinds_of(after.settings);  // as the module holds them now
  std::vector<PlannedChange> changes;
  for (const auto& [name, raw] : wanted) {
    const Register* r = registers::find_register(name);
    if (!r || r->unit != Unit::module || r->table != Table::holding_register)
      return std::unexpected(fmt::format("'{}' is not a setting (module holding register)", name));
    if (check && (raw < r->min || raw > r->max))
      return std::unexpected(fmt::format("{} = {} is outside its range {}; nothing was written", name,
                                         value_text(*r, raw, kinds), accepted_text(*r, kinds)));
    const auto it = current.find(name);
    if (it == current.end()) return std::unexpected(fmt::format("internal: current value of {} not read", name));
    if (it->second == raw) continue;
    changes.push_back({r, it->second, raw});
    apply_raw(after.settings, after.host, *r, raw);
  }
  return changes;
}

// One block per run touched, from the first to the last changed word, the
// words in between at their current values; at most 123 registers a request.
std::expected<std::vector<Block>, std::string> blocks_of(const std::vector<PlannedChange>& changes,
                                                         const RawMap& current, const RawMap& wanted,
                                                         registers::WordOrder order) {
  auto word_of = [&](std::uint16_t address, bool new_value) -> std::uint16_t {
    const Register* r = registers::find_register(Unit::module, Table::holding_register, address);
    if (!r) return 0;
    std::int64_t raw = current.at(r->name());
    if (new_value)
      if (auto w = wanted.find(r->name()); w != wanted.end()) raw = w->second;
    std::uint16_t words[2];
    registers::encode_words(*r, raw, order, std::span<std::uint16_t>(words, r->words()));
    return words[address - r->address];
  };
  std::vector<Block> blocks;
  for (const Run& run : holding_runs()) {
    std::uint32_t lo = UINT32_MAX, hi = 0;
    for (const auto& c : changes)
      if (c.reg->address >= run.start && c.reg->end() <= run.end) {
        lo = std::min<std::uint32_t>(lo, c.reg->address);
        hi = std::max(hi, c.reg->end());
      }
    if (lo == UINT32_MAX) continue;
    for (std::uint32_t a = lo; a < hi; ++a) {
      const Register* r = registers::find_register(Unit::module, Table::holding_register, static_cast<std::uint16_t>(a));
      if (r && !current.contains(r->name()))
        return std::unexpected(fmt::format("internal: current value of {} not read", r->name()));
    }
    Block b;
    b.start = static_cast<std::uint16_t>(lo);
    for (std::uint32_t a = lo; a < hi; ++a) {
      b.words.push_back(word_of(static_cast<std::uint16_t>(a), true));
    }
    while (b.words.size() > 123) {
      Block head{b.start, {b.words.begin(), b.words.begin() + 120}};
      blocks.push_back(head);
      b.start = static_cast<std::uint16_t>(b.start + 120);
      b.words.erase(b.words.begin(), b.words.begin() + 120);
    }
    blocks.push_back(b);
  }
  return blocks;
}

}  // namespace

std::expected<WritePlan, std::string> plan_write(const RawMap& current, const RawMap& wanted,
                                                 registers::WordOrder order, bool check) {
  const ModuleState before = state_of(current);
  ModuleState after = before;
  auto changes = changes_of(current, wanted, check, after);
  if (!changes) return std::unexpected(changes.error());
  WritePlan plan;
  plan.changes = std::move(*changes);
  plan.kinds = registers::kinds_of(after.settings);
  if (plan.changes.empty()) return plan;

  // The final settings must pass the engine's rule set, as the daemon runs it.
  if (check)
    if (auto f = homing::new_fault(before.settings, after.settings))
      return std::unexpected(fmt::format("{}; nothing was written", homing::describe_fault(*f, after.settings)));

  // Staged in one edit session and checked together at its commit: any order.
  auto blocks = blocks_of(plan.changes, current, wanted, order);
  if (!blocks) return std::unexpected(blocks.error());
  plan.blocks = std::move(*blocks);
  return plan;
}

std::string refusal_reason(Connection& c, Unit written) {
  const std::int64_t code = c.read("status.last_refusal_reason");
  const Register& reason = register_named("status.last_refusal_reason");
  for (const registers::EnumValue& v : reason.values)
    if (v.value == code) {
      const std::int64_t at = c.read("status.last_refused_register");
      const Register* about = registers::find_register(written, Table::holding_register, static_cast<std::uint16_t>(at));
      return fmt::format("{}{}{}", v.meaning, about ? " (about " : "", about ? about->name() + ")" : "");
    }
  return fmt::format("reason {}", code);
}

// One edit session (docs/hmi-integration.md "Edit sessions"): every block is
// staged, then the commit checks them together and applies all or none, in
// one transaction, so neither another client nor a power cut ever sees the
// change half made. On any refusal the session is discarded.
std::expected<void, std::string> execute_plan(Connection& c, const WritePlan& plan) {
  if (plan.blocks.empty()) return {};
  const Register& edit = register_named("edit.command");
  if (const int ex = c.write(edit, 1))
    return std::unexpected(fmt::format("the module refused to begin an edit session: {}: {}", exception_sentence(ex),
                                       refusal_reason(c, Unit::module)));
  auto give_up = [&](std::string what) -> std::expected<void, std::string> {
    (void)c.write(edit, 3);  // discard: nothing of it was applied
    return std::unexpected(std::move(what) + "; nothing was changed");
  };
  for (const Block& b : plan.blocks)
    if (const int ex = c.write_words(Unit::module, b.start, b.words))
      return give_up(fmt::format("the module refused: {}: {}", exception_sentence(ex), refusal_reason(c, Unit::module)));
  if (const int ex = c.write(edit, 2))
    return give_up(fmt::format("the module refused the change at its commit: {}: {}", exception_sentence(ex),
                               refusal_reason(c, Unit::module)));
  return {};
}

// ------------------------------------------------------------------ file
// The layout is persistence's (persistence/settings_file.hpp), the spelling of
// the values the register layer's: a file exported here imports into a
// database and the other way round.

namespace {

const persistence::SettingsFileCodec& codec() {
  static const persistence::SettingsFileCodec c{registers::file_value_text, registers::raw_of_file_value};
  return c;
}

std::string problems_text(const std::string& file, const std::vector<std::string>& problems) {
  if (problems.size() == 1) return problems.front() + "; nothing was imported";
  std::string s = fmt::format("{}: {} values cannot be imported; nothing was imported:", file, problems.size());
  for (const auto& p : problems) s += "\n  " + p;
  return s;
}

}  // namespace

std::string settings_file_text(const RawMap& values, const std::string& source, std::int64_t now_ms) {
  return persistence::settings_file_text(values, source, now_ms, &codec());
}

std::string file_value_text(const registers::Register& reg, std::int64_t raw) {
  std::string text = registers::file_value_text(reg.name(), raw, {});  // the unit comment is cut
  if (const auto comment = text.find("  #"); comment != std::string::npos) text.resize(comment);
  return text;
}

std::expected<void, std::string> write_file_atomically(const std::string& path, const std::string& text) {
  if (auto w = persistence::write_file_atomically(path, text); !w) return std::unexpected(w.error().message);
  return {};
}

std::expected<SettingsFileValues, std::string> read_settings_file(const std::string& file) {
  auto parsed = persistence::read_settings_file(file);
  if (!parsed) return std::unexpected(parsed.error().message);
  SettingsFileValues out;
  std::vector<std::string> problems;
  for (const auto& [name, e] : parsed->entries) {
    const Register* r = registers::find_register(name);
    if (!r || r->unit != Unit::module || r->table != Table::holding_register || !r->persisted)
      problems.push_back(fmt::format("{}:{}: unknown register '{}'", file, e.line, name));
    out.lines[name] = e.line;
  }
  if (!problems.empty()) return std::unexpected(problems_text(file, problems));
  auto raw = persistence::raw_values(file, *parsed, &codec());
  if (!raw) return std::unexpected(raw.error().message);
  for (const auto& [name, value] : *raw) {  // a raw (version 1) file is range-checked here
    const Register& r = register_named(name);
    if (value < r.min || value > r.max)
      problems.push_back(fmt::format("{}:{}: '{}' = {} is outside its range {}", file, out.lines.at(name), name, value,
                                     accepted_text(r)));
  }
  if (!problems.empty()) return std::unexpected(problems_text(file, problems));
  out.values = std::move(*raw);
  return out;
}

}  // namespace homingctl
