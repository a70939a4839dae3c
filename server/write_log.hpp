#pragma once
// How the Modbus service names, in its log and in the settings history, who
// wrote and what a write changed.
#include <string>
#include <vector>

#include "persistence/settings_store.hpp"
#include "registers/validate.hpp"
#include "request_handler.hpp"

namespace server {

// Who changed a setting, for the audit log: over TLS also the certificate's
// subject and role.
persistence::ChangeSource source_of(const ClientInfo& client);

// "axis.x.pull_off: 2 mm -> 2.5 mm; ..." in engineering units, each axis's
// in the unit of the kind it moves with (registers::kinds_of the settings).
std::string describe_changes(const std::vector<registers::Change>& changes, const registers::AxisKinds& kinds);

}  // namespace server
