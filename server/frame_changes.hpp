#pragma once
// What a settings change costs the axes' references, in words for the log.
// The engine forgets an axis's home when a setting that places its
// coordinates changes (homing/home_frame.hpp); it cannot log, and a
// technician who wrote a home position should read why the axis is no longer
// homed rather than find phase `done` beside homed 0. Pure.
#include <string>
#include <vector>

#include "homing/settings.hpp"
#include "homing/status.hpp"

namespace server {

// One line per axis that is homed, or offered a reference check, in `status`
// and whose home frame differs between `before` and `after` (configured
// settings: a gantry slave's frame is its master's).
std::vector<std::string> references_lost(const homing::Settings& before, const homing::Settings& after,
                                         const homing::Status& status);

}  // namespace server
