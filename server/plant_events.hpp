#pragma once
// What the plant hears of this module besides its values: homing cycles,
// alarms with their text, and settings changes, kept in the MQTT event outbox
// (persistence/event_outbox.hpp) as they happen, whether or not a broker is
// reachable. The monitor's thread feeds it; the MQTT node sends what it holds.
#include <cstdint>

#include "homing/settings.hpp"
#include "homing/status.hpp"
#include "persistence/event_outbox.hpp"
#include "persistence/settings_store.hpp"
#include "status_events.hpp"

namespace server {

class PlantEvents {
 public:
  // The settings store is where settings changes are read from (its audit
  // log); nullptr: settings changes are not reported.
  PlantEvents(persistence::EventOutbox& outbox, persistence::SettingsStore* store);

  // Alarms raised, alarms reset, homing cycles started and ended, as the
  // control loop recorded them period by period (the snapshot's ring).
  void take(const StatusEvents& ring, const homing::Settings& settings);
  // Settings changes committed since the last call (the audit log's new rows).
  void settings_changes();

 private:
  void keep(persistence::Event event, std::optional<std::int64_t> audit_id = std::nullopt);

  std::uint64_t taken_ = 0;  // the last ring event kept
  persistence::EventOutbox& outbox_;
  persistence::SettingsStore* store_;
};

}  // namespace server
