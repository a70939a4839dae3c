#include "frame_changes.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>

#include "homing/axes.hpp"
#include "homing/gantry.hpp"
#include "homing/home_frame.hpp"

namespace server {
namespace {

// The settings (their register names after axis.<a>.) that differ.
std::vector<std::string> changed_fields(const homing::HomeFrame& a, const homing::HomeFrame& b) {
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
  return names;
}

}  // namespace

std::vector<std::string> references_lost(const homing::Settings& before, const homing::Settings& after,
                                         const homing::Status& status) {
  const homing::Settings was = homing::motion_settings(before);
  const homing::Settings is = homing::motion_settings(after);
  // Why each axis loses its reference: its own frame, or its gantry
  // partner's (a pair shares one reference, as the engine's keep_home_frames has it).
  std::array<std::string, homing::kAxisCount> why{};
  const auto homed = [&](std::size_t a) {
    return status.axes[a].trust == homing::Trust::homed_this_power_on ||
           status.axes[a].trust == homing::Trust::reference_checked;
  };
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const homing::HomeFrame old_frame = homing::home_frame(was.axes[a]);
    const homing::HomeFrame new_frame = homing::home_frame(is.axes[a]);
    if (old_frame == new_frame) continue;
    std::vector<std::string> names = changed_fields(old_frame, new_frame);
    const std::string fields = fmt::format("{}", fmt::join(names, ", "));
    // A slave moves with most of its master's settings: name whose changed.
    if (const int m = homing::gantry_master(after, a); m >= 0) {
      const auto mi = static_cast<std::size_t>(m);
      const auto masters = changed_fields(homing::home_frame(before.axes[mi]), homing::home_frame(after.axes[mi]));
      for (std::string& n : names)
        if (std::find(masters.begin(), masters.end(), n) != masters.end())
          n += fmt::format(" of its gantry master {}", homing::kAxisLetters[mi]);
    }
    why[a] = fmt::format("{} changed, which places its coordinates", fmt::join(names, ", "));
    // The engine unhomes the partner of an axis that was homed; a clean
    // stop's offer is withdrawn only by the axis's own frame.
    if (!homed(a)) continue;
    for (const homing::Settings* s : {&before, &after})
      for (const int p : {homing::gantry_master(*s, a), homing::gantry_slave(*s, a)}) {
        if (p < 0) continue;
        std::string& partner = why[static_cast<std::size_t>(p)];
        if (partner.empty() && homed(static_cast<std::size_t>(p)))
          partner = fmt::format("its gantry partner {} lost its reference ({} of {} changed), and a pair shares one",
                                homing::kAxisLetters[a], fields, homing::kAxisLetters[a]);
      }
  }
  std::vector<std::string> lines;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    if (why[a].empty()) continue;
    const auto letter = homing::kAxisLetters[a];
    const std::string& what = why[a];
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
