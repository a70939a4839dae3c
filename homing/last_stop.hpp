#pragma once
// What the runtime keeps of each axis when the module stops (trust.hpp): one
// rule for homingd's clean shutdown and for the tests that restart an engine.
#include "io.hpp"
#include "settings.hpp"
#include "status.hpp"
#include "trust.hpp"

namespace homing {

// The last stops at a clean shutdown, from the last period's status and
// outputs: an axis is a clean stop when it is homed (by a cycle or a
// reference check), at rest, its drive enabled, and no alarm is latched
// anywhere; each records its position and the frame its settings give it.
LastStops last_stops_at_shutdown(const Settings& settings, const Status& status, const Outputs& outputs);

}  // namespace homing
