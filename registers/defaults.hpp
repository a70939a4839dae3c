#pragma once
// Defaults and the keyed form of the settings for the SQLite store. The
// table's default column is the only source of defaults; the SQLite keys are
// the register names, the values raw register integers.
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "homing/settings.hpp"
#include "registers/codec.hpp"

namespace registers {

// Settings built from the default column of every persisted holding register.
homing::Settings default_settings();
// Host values (heartbeat, targets, coils) at their defaults.
HostRegisters default_host_registers();

// name -> raw default of every persisted register, in address order: the rows
// of a new database.
std::vector<std::pair<std::string, std::int64_t>> persisted_defaults();

// name -> raw value of every persisted register.
std::map<std::string, std::int64_t> settings_to_raw(const homing::Settings& settings);

// Settings from stored rows. A missing name gets its default (a newer build
// added it); a stored value outside today's range gets its default too and is
// reported; unknown names are reported and ignored (a register retired).
struct SettingsFromRaw {
  homing::Settings settings;
  std::vector<std::string> defaulted;  // names missing in the store
  std::vector<std::string> rejected;   // "axis.x.seek_feedrate = 90000 is outside 1..60000; default used"
  std::vector<std::string> unknown;    // stored names that no register has
  bool complete() const { return defaulted.empty() && rejected.empty(); }
};
SettingsFromRaw settings_from_raw(const std::map<std::string, std::int64_t>& stored);

}  // namespace registers
