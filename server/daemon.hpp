#pragma once
// homingd serving: the control loop and the machine (simulator or GPIO)
// behind, Modbus TCP and RTU in front, settings in SQLite, until SIGINT or
// SIGTERM.
#include <optional>

#include "homing/gpiod/config.hpp"
#include "options.hpp"

namespace server {

// wiring: the GPIO lines (--backend gpiod), nullopt for the simulator.
// Exit code: 0 after a clean stop, 1 when it could not start (the reason on stderr).
int run_daemon(const Options& opt, const std::optional<homing::gpiod::BackendConfig>& wiring);

}  // namespace server
