#include "registers/validate.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "homing/gantry.hpp"
#include "homing/settings_check.hpp"
#include "registers/defaults.hpp"
#include "registers/lookup.hpp"

namespace registers {
namespace {

Refusal address_fault(RefusalReason reason, std::uint32_t address, std::string message) {
  return Refusal::because(reason, static_cast<std::uint16_t>(address), std::move(message));
}

// A broken rule, about the register of the setting the fault names.
Refusal rule_refusal(const homing::SettingsFault& fault, std::string message) {
  const Register* reg = find_register(
      fmt::format("axis.{}.{}", homing::kAxisLetters[fault.axis], homing::field_name(fault.field)));
  return Refusal::because(RefusalReason::rule, reg ? reg->address : std::uint16_t{0}, std::move(message),
                          fault.rule);
}

std::string where(Unit unit, Table table, std::uint32_t address) {
  return fmt::format("{} {} ({}) of the {} unit", table_name(table), address,
                     modbus_reference(table, static_cast<std::uint16_t>(address)), unit_name(unit));
}

std::string range_text(const Register& reg, const AxisKinds& kinds) {
  const auto unit = reg.unit_text(kinds);
  return fmt::format("{}..{}{}{}", to_engineering(reg, reg.min), to_engineering(reg, reg.max),
                     unit.empty() ? "" : " ", unit);
}

std::uint16_t home_axes_address() {
  const Register* reg = find_register("cmd.home_axes");
  return reg ? reg->address : std::uint16_t{0};
}

// A cmd.home_axes mask names at least one axis, and only axes that home.
std::optional<Refusal> named_axes_refusal(const CommandRequest& c, const homing::Settings& settings) {
  if (c.command != Command::home_axes) return std::nullopt;
  const std::uint16_t address = home_axes_address();
  if (c.axes == 0)
    return Refusal::because(
        RefusalReason::no_axis_named, address,
        "cmd.home_axes = 0 names no axis: set bit 0 (X) ... bit 5 (C) of the axes to home; nothing was written");
  for (std::size_t a = 0; a < homing::kAxisCount; ++a)
    if ((c.axes & homing::axis_bit(a)) && settings.axes[a].mode == homing::HomingMode::disabled)
      return Refusal::because(RefusalReason::axis_disabled, address,
                              fmt::format("cmd.home_axes names {0}, whose axis.{1}.mode is disabled: {0} cannot be "
                                          "homed; nothing was written",
                                          homing::kAxisUpper[a], homing::kAxisLetters[a]));
  return std::nullopt;
}

}  // namespace

std::expected<std::vector<RawWrite>, Refusal> decode_write(Unit unit, Table table, std::uint16_t start,
                                                            std::span<const std::uint16_t> values,
                                                            WordOrder order, const AxisKinds& kinds) {
  if (values.empty())
    return std::unexpected(
        Refusal::because(RefusalReason::empty, start, "a write of 0 items"));
  const std::uint32_t end = std::uint32_t{start} + static_cast<std::uint32_t>(values.size());
  if (end > 65536)
    return std::unexpected(address_fault(RefusalReason::not_mapped, start,
                                         fmt::format("write {}..{} runs past address 65535", start, end - 1)));

  std::vector<RawWrite> out;
  std::optional<Refusal> value_fault;  // reported only when every address is fine
  for (std::uint32_t a = start; a < end;) {
    const Register* reg = find_register(unit, table, static_cast<std::uint16_t>(a));
    if (!reg)
      return std::unexpected(address_fault(
          RefusalReason::not_mapped, a,
          fmt::format("{} is not mapped; nothing was written (see hmi_maps/)", where(unit, table, a))));
    if (!reg->writable() || table == Table::input_register || table == Table::discrete_input)
      return std::unexpected(address_fault(
          RefusalReason::read_only, a,
          fmt::format("{} ({}) is read-only; nothing was written", reg->name(), where(unit, table, a))));
    if (reg->address != a)
      return std::unexpected(address_fault(
          RefusalReason::split_32bit, reg->address,
          fmt::format(
          "{} is 32-bit ({}..{}); this write starts at its second word {}: write both words in one request",
          reg->name(), reg->address, reg->address + 1, a)));
    if (reg->end() > end)
      return std::unexpected(address_fault(
          RefusalReason::split_32bit, reg->address,
          fmt::format(
          "{} is 32-bit ({}..{}); this write ends after its first word: write both words in one request",
          reg->name(), reg->address, reg->address + 1)));

    const auto words = values.subspan(a - start, reg->words());
    std::int64_t raw = 0;
    if (table == Table::coil) {
      raw = words[0] != 0 ? 1 : 0;
    } else {
      raw = decode_words(*reg, words, order);
    }
    if ((raw < reg->min || raw > reg->max) && !value_fault)
      value_fault = Refusal::because(RefusalReason::out_of_range, reg->address,
                                     fmt::format("{} = {} is outside its range {}; nothing was written",
                                                 reg->name(), format_value(*reg, raw, kinds), range_text(*reg, kinds)));
    out.push_back({reg, raw});
    a = reg->end();
  }
  if (value_fault) return std::unexpected(*value_fault);
  return out;
}

bool AcceptedWrite::changes_persisted() const {
  return std::any_of(changes.begin(), changes.end(), [](const Change& c) { return c.reg->persisted; });
}

// A change to a setting a gantry slave takes from its master, while it is a
// slave before and after the request: it would change nothing. (A request
// that makes the axis a slave may still carry its own values: they are
// then the ones it returns to when it is no longer one.)
std::optional<Refusal> slave_inherits_refusal(const std::vector<Change>& changes, const homing::Settings& before,
                                              const homing::Settings& after) {
  for (const Change& c : changes) {
    const Register& reg = *c.reg;
    if (!reg.persisted || !reg.per_axis()) continue;
    const auto axis = static_cast<std::size_t>(reg.axis);
    const int master = homing::gantry_master(after, axis);
    if (master < 0 || homing::gantry_master(before, axis) != master) continue;
    const std::string name = reg.name();
    const std::string_view field_name = std::string_view(name).substr(name.find('.', 5) + 1);
    homing::AxisField field = homing::AxisField::none;
    for (const auto& f : homing::kAxisFieldInfo)
      if (f.name == field_name) field = f.value;
    if (!homing::inherited_from_master(field, after.axes[axis].slave_mode)) continue;
    const std::string master_reg = fmt::format("axis.{}.{}", homing::kAxisLetters[static_cast<std::size_t>(master)], field_name);
    const Register* on_master = find_register(master_reg);
    return Refusal::because(
        RefusalReason::slave_inherits, on_master ? on_master->address : reg.address,
        fmt::format("{}: {} is a gantry slave of {} and homes and moves with {}'s {}; write {} instead; nothing "
                    "was written",
                    name, homing::kAxisUpper[axis], homing::kAxisUpper[static_cast<std::size_t>(master)],
                    homing::kAxisUpper[static_cast<std::size_t>(master)], field_name, master_reg));
  }
  return std::nullopt;
}

std::expected<AcceptedWrite, Refusal> validate_write(Table table, std::uint16_t start,
                                                     std::span<const std::uint16_t> values, WordOrder order,
                                                     const homing::Settings& settings,
                                                     const HostRegisters& host) {
  auto decoded = decode_write(Unit::module, table, start, values, order, kinds_of(settings));
  if (!decoded) return std::unexpected(decoded.error());
  return validate_raw_writes(*decoded, settings, host);
}

std::expected<AcceptedWrite, Refusal> validate_raw_writes(std::span<const RawWrite> writes,
                                                          const homing::Settings& settings,
                                                          const HostRegisters& host) {
  AcceptedWrite result{{}, settings, host, {}};
  for (const RawWrite& w : writes) {
    const Register& reg = *w.reg;
    std::int64_t old_raw = 0;
    if (reg.table == Table::coil) {
      if (auto cmd = command_of(reg, w.raw != 0); cmd && (w.raw != 0 || cmd->command == Command::jog_plus ||
                                                          cmd->command == Command::jog_minus ||
                                                          cmd->command == Command::homing_permit))
        result.commands.push_back(*cmd);
      if (reg.access == Access::w) continue;  // pulse commands hold no state
      old_raw = host_raw(result.host, reg);
      set_host_raw(result.host, reg, w.raw);
    } else if (auto cmd = command_of(reg, w.raw)) {
      result.commands.push_back(*cmd);
      continue;  // a command register holds nothing
    } else if (reg.persisted) {
      old_raw = setting_raw(result.settings, reg);
      set_setting_raw(result.settings, reg, w.raw);
    } else {
      old_raw = host_raw(result.host, reg);
      set_host_raw(result.host, reg, w.raw);
    }
    if (old_raw != w.raw) result.changes.push_back({&reg, old_raw, w.raw});
  }

  if (auto refused = slave_inherits_refusal(result.changes, settings, result.settings)) return std::unexpected(*refused);

  // The engine's own rule set, on the settings as they would be after the
  // request: a write may not break a rule (the whole configuration is checked,
  // so a write to a master that breaks its slave is refused too).
  if (const auto fault = homing::new_fault(settings, result.settings))
    return std::unexpected(
        rule_refusal(*fault, fmt::format("{}; nothing was written", homing::describe_fault(*fault, result.settings))));
  for (const CommandRequest& c : result.commands)
    if (auto refused = named_axes_refusal(c, result.settings)) return std::unexpected(*refused);
  return result;
}

std::optional<Refusal> refusal_now(const AcceptedWrite& write, const homing::Status& status) {
  for (const CommandRequest& c : write.commands) {
    if (c.command != Command::home_axes) continue;
    const homing::CommandResult r = homing::homing_refusal_of(status.interlocks);
    if (r == homing::CommandResult::accepted) continue;
    return Refusal::because(
        r == homing::CommandResult::refused_busy ? RefusalReason::busy : RefusalReason::homing_blocked,
        home_axes_address(),
        fmt::format("cmd.home_axes refused ({}): {}; nothing was written", homing::command_result_name(r),
                    homing::kCommandResultInfo[static_cast<std::size_t>(r)].text));
  }
  return std::nullopt;
}

std::optional<Refusal> validate_settings_map(const std::map<std::string, std::int64_t>& values) {
  const SettingsFromRaw decoded = settings_from_raw(values);
  const AxisKinds kinds = kinds_of(decoded.settings);
  for (const auto& [name, raw] : values) {
    const Register* reg = find_register(name);
    if (!reg || !reg->persisted)
      return Refusal::because(RefusalReason::not_mapped, 0, fmt::format("{} is not a setting of this module", name));
    if (raw < reg->min || raw > reg->max)
      return Refusal::because(
          RefusalReason::out_of_range, reg->address,
          fmt::format("{} = {} is outside its range {}", name, format_value(*reg, raw, kinds),
                      range_text(*reg, kinds)));
  }
  for (const auto& fault : homing::check_settings(decoded.settings))
    if (fault) return rule_refusal(*fault, homing::describe_fault(*fault, decoded.settings));
  return std::nullopt;
}

}  // namespace registers
