#pragma once
// What every mode of homingd does before its own job: report a failure to
// start, read the machine's wiring, open the settings database.
#include <expected>
#include <optional>
#include <string>

#include "homing/gpiod/config.hpp"
#include "options.hpp"
#include "persistence/settings_store.hpp"

namespace server {

// Prints "homingd: <message>" to stderr; returns the exit code 1.
int fail_start(const std::string& message);

// The GPIO lines named in the config file's [gpiod] table with --backend
// gpiod (nullopt with the simulator); the error names the option and the
// mistake.
std::expected<std::optional<homing::gpiod::BackendConfig>, std::string> read_wiring(const Options& opt);

// The settings database of --db, created from the register table's defaults
// on first start; the error names --db and the reason.
std::expected<persistence::SettingsStore, std::string> open_settings(const Options& opt);

}  // namespace server
