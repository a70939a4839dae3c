#include "frame_changes.hpp"

#include <fmt/format.h>

#include "homing/axes.hpp"
#include "homing/gantry.hpp"
#include "homing/home_frame.hpp"

namespace server {
namespace {

// The settings (their register names after axis.<a>.) that differ.
std::string changed_fields(const homing::HomeFrame& a, const homing::HomeFrame& b) {
  std::vector<std::string> names;
  if (a.mode != b.mode) names.emplace_back("mode");
  if (a.direction != b.direction) names.emplace_back("direction");
  if (a.sensor_nc != b.sensor_nc) names.emplace_back("sensor_nc");
  if (a.slave_of != b.slave_of) names.emplace_back("slave_of");
  if (a.slave_mode != b.slave_mode) names.emplace_back("slave_mode");
  if (a.pull_off_mm != b.pull_off_mm) names.emplace_back("pull_off");
  if (a.switch_compensation_mm != b.switch_compensation_mm) names.emplace_back("switch_compensation");
  if (a.home_position_mm != b.home_position_mm) names.emplace_back("home_position");
  if (a.cam_edge != b.cam_edge) names.emplace_back("cam_edge");
  return fmt::format("{}", fmt::join(names, ", "));
}

}  // namespace

std::vector<std::string> references_lost(const homing::Settings& before, const homing::Settings& after,
                                         const homing::Status& status) {
  const homing::Settings was = homing::motion_settings(before);
  const homing::Settings is = homing::motion_settings(after);
  std::vector<std::string> lines;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const homing::HomeFrame old_frame = homing::home_frame(was.axes[a]);
    const homing::HomeFrame new_frame = homing::home_frame(is.axes[a]);
    if (old_frame == new_frame) continue;
    const auto letter = homing::kAxisLetters[a];
    const int master = homing::gantry_master(after, a);
    const std::string whose =
        master >= 0 ? fmt::format(" (of its gantry master {})", homing::kAxisLetters[static_cast<std::size_t>(master)])
                    : std::string{};
    const std::string what = fmt::format("{} changed{}, which places its coordinates", changed_fields(old_frame, new_frame), whose);
    switch (status.axes[a].trust) {
      case homing::Trust::homed_this_power_on:
      case homing::Trust::reference_checked:
        lines.push_back(fmt::format("axis {} is no longer homed: {}; home it again before moving it by coordinates",
                                    letter, what));
        break;
      case homing::Trust::last_stop_clean:
        lines.push_back(fmt::format("axis {}: the reference check its clean stop offered is withdrawn: {}; home it "
                                    "with a full cycle",
                                    letter, what));
        break;
      case homing::Trust::unknown: break;
    }
  }
  return lines;
}

}  // namespace server
