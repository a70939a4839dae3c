#include "client_role.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "registers/lookup.hpp"

namespace server {
namespace {

// A writable row of the module that an operator runs the machine with. Every
// other writable row (settings, and any row added later) needs an engineer.
bool is_operating_row(const registers::Register& reg) {
  using registers::Key;
  switch (reg.key) {
    case Key::cmd_home_all:
    case Key::cmd_home:
    case Key::cmd_home_axes:
    case Key::cmd_unhome:
    case Key::cmd_refcheck:
    case Key::cmd_abort:
    case Key::cmd_reset_alarm:
    case Key::cmd_jog_plus:
    case Key::cmd_jog_minus:
    case Key::cmd_move:
    case Key::host_target:
    case Key::host_heartbeat:
    case Key::host_homing_permit: return true;
    default: return false;
  }
}

}  // namespace

std::optional<Access> access_of_role(std::string_view role) {
  const auto row = std::find_if(kRoles.begin(), kRoles.end(), [&](const RoleRow& r) { return r.name == role; });
  if (row == kRoles.end()) return std::nullopt;
  return row->access;
}

std::string_view access_name(Access access) {
  switch (access) {
    case Access::read_only: return "read-only";
    case Access::commands: return "commands";
    case Access::settings: return "settings";
  }
  return "?";
}

Access access_needed(registers::Unit unit, registers::Table table, std::uint16_t start, std::size_t count) {
  if (unit == registers::Unit::simulator) return Access::settings;
  Access needed = Access::commands;
  for (std::size_t i = 0; i < count && start + i <= 0xFFFF; ++i) {
    const auto* reg = registers::find_register(unit, table, static_cast<std::uint16_t>(start + i));
    if (reg && reg->writable() && !is_operating_row(*reg)) needed = Access::settings;
  }
  return needed;
}

std::optional<std::string> access_refusal(const ClientInfo& client, registers::Unit unit, registers::Table table,
                                          std::uint16_t start, std::size_t count) {
  if (client.access == Access::settings) return std::nullopt;
  if (client.access == Access::read_only) return fmt::format("{} may only read", client.identity);
  if (access_needed(unit, table, start, count) <= client.access) return std::nullopt;
  const bool sim = unit == registers::Unit::simulator;
  return fmt::format("{} may not write {} (an engineer's)", client.identity,
                     sim ? "the simulator unit" : "settings, the unlock code or the settings lock");
}

}  // namespace server
