#pragma once
// Position trust across restarts (homing/trust.hpp): what homingd keeps of
// each axis's last stop in its database, and the simulator's carriages.
// Start-up reads the last stops for the engine and wipes their clean marks
// at once, durably, before anything can move: only a clean shutdown writes
// them again, so a run that ends any other way (SIGKILL, a power cut, a
// crash) leaves no axis trusted.
#include <array>
#include <optional>

#include "control_loop.hpp"
#include "homing/settings.hpp"
#include "homing/trust.hpp"
#include "persistence/settings_store.hpp"

namespace server {

// The kept last stops in the engine's terms, and back.
homing::LastStops to_engine(const persistence::LastStops& stored);
persistence::LastStops to_store(const homing::LastStops& stops);

// At start: the last stops to give the engine (each logged), their clean
// marks wiped. nullopt when they cannot be read, or the marks cannot be
// wiped (then nothing is trusted this run: an unclean end could not be told).
std::optional<homing::LastStops> take_last_stops(persistence::SettingsStore& store, const homing::Settings& settings);

// At a clean shutdown: the stops the loop ended with (StopReport), and the
// simulator's carriages.
void keep_last_stops(persistence::SettingsStore& store, const StopReport& report);

// Where the simulator's carriages were kept (nullopt per axis: never).
persistence::SimCarriages kept_sim_carriages(persistence::SettingsStore& store);

}  // namespace server
