#pragma once
// Who may change what over Modbus/TCP Security: the role in a client's
// certificate (tls/certificate.hpp) grants an Access (request_handler.hpp),
// and each write needs one. One table; the README's security section shows
// the same.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "registers/table.hpp"
#include "request_handler.hpp"

namespace server {

struct RoleRow {
  std::string_view name;  // as in the certificate's role extension
  Access access;
  std::string_view grants;
};

inline constexpr std::array kRoles{
    RoleRow{"viewer", Access::read_only, "reads every register, coil and trace; writes nothing"},
    RoleRow{"operator", Access::commands,
            "also commands (home, abort, reset, jog, move), the move targets, the heartbeat and the homing permit"},
    RoleRow{"engineer", Access::settings,
            "also settings, the unlock code and the settings lock, and the simulator unit"},
};

// The access a role grants; nullopt for a name that is not in kRoles.
std::optional<Access> access_of_role(std::string_view role);

// "read-only", "commands", "settings".
std::string_view access_name(Access access);

// What a write to these addresses needs: settings rows, security.unlock,
// cmd.lock_settings and the simulator unit need Access::settings; the other
// writable rows (commands, heartbeat, move targets, homing permit) need
// Access::commands, as does a write to an address that is not writable (the
// usual checks then answer it). `count` words or coils from `start`.
Access access_needed(registers::Unit unit, registers::Table table, std::uint16_t start, std::size_t count);

// Why `client` may not make this write ("role viewer may only read"), or
// nullopt when its access suffices.
std::optional<std::string> access_refusal(const ClientInfo& client, registers::Unit unit, registers::Table table,
                                          std::uint16_t start, std::size_t count);

}  // namespace server
