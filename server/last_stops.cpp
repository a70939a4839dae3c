#include "last_stops.hpp"

#include <spdlog/spdlog.h>

#include "homing/gantry.hpp"

namespace server {

namespace {

persistence::StoredFrame to_store(const homing::HomeFrame& f) {
  return persistence::StoredFrame{static_cast<std::int64_t>(f.mode),       static_cast<std::int64_t>(f.direction),
                                  f.sensor_nc,                               static_cast<std::int64_t>(f.slave_of),
                                  static_cast<std::int64_t>(f.slave_mode), f.pull_off_mm,
                                  f.switch_compensation_mm,                 f.home_position_mm,
                                  static_cast<std::int64_t>(f.cam_edge)};
}

homing::HomeFrame to_engine(const persistence::StoredFrame& f) {
  homing::HomeFrame h;
  h.mode = static_cast<homing::HomingMode>(f.mode);
  h.direction = static_cast<homing::Direction>(f.direction);
  h.sensor_nc = f.sensor_nc;
  h.slave_of = static_cast<std::uint8_t>(f.slave_of);
  h.slave_mode = static_cast<homing::SlaveMode>(f.slave_mode);
  h.pull_off_mm = f.pull_off_mm;
  h.switch_compensation_mm = f.switch_compensation_mm;
  h.home_position_mm = f.home_position_mm;
  h.cam_edge = static_cast<homing::CamEdge>(f.cam_edge);
  return h;
}

// One line per axis kept: what its next start may do with it.
void log_last_stop(std::size_t a, const persistence::AxisLastStop& s, const homing::Settings& settings) {
  const char axis = homing::kAxisUpper[a];
  const auto unit = homing::axis_unit(settings, a);
  if (!s.clean) {
    spdlog::info("last stop: {} at {:.3f} {} was not a clean stop (not homed, an alarm, or not shut down by "
                 "SIGTERM/SIGINT): trust unknown, home it with a full cycle",
                 axis, s.position_mm, unit);
    return;
  }
  const homing::Settings motion = homing::motion_settings(settings);
  if (to_engine(s.frame) != homing::home_frame(motion.axes[a])) {
    spdlog::info("last stop: {} stopped cleanly at {:.3f} {}, but its home settings changed since: trust unknown, "
                 "home it with a full cycle",
                 axis, s.position_mm, unit);
    return;
  }
  // What cmd.refcheck would say (homing/refcheck.cpp): no offer it then refuses.
  const bool paired = homing::gantry_partner(settings, a) >= 0 || homing::master_of(settings.axes[a]) >= 0;
  spdlog::info("last stop: {} stopped cleanly at {:.3f} {}: trust last_stop_clean{}", axis, s.position_mm, unit,
               paired ? " (one side of a gantry pair cannot be checked alone: home the pair with a full cycle)"
               : homing::offers_refcheck(motion.axes[a].mode)
                   ? "; a reference check (cmd.refcheck, homingctl refcheck) may home it without a full cycle"
                   : " (its method has no switch edge to check: home it with a full cycle)");
}

}  // namespace

homing::LastStops to_engine(const persistence::LastStops& stored) {
  homing::LastStops out{};
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    if (!stored[a]) continue;
    out[a].clean = stored[a]->clean;
    out[a].position_mm = stored[a]->position_mm;
    out[a].frame = to_engine(stored[a]->frame);
  }
  return out;
}

persistence::LastStops to_store(const homing::LastStops& stops) {
  persistence::LastStops out{};
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    persistence::AxisLastStop s;
    s.clean = stops[a].clean;
    s.position_mm = stops[a].position_mm;
    s.frame = to_store(stops[a].frame);
    out[a] = s;
  }
  return out;
}

std::optional<homing::LastStops> take_last_stops(persistence::SettingsStore& store, const homing::Settings& settings) {
  auto stored = store.last_stops();
  if (!stored) {
    spdlog::error("last stops not read, no axis is offered a reference check: {}", stored.error().message);
    return std::nullopt;
  }
  if (auto wiped = store.clear_clean_stops(); !wiped) {
    spdlog::error("last stops: the clean marks could not be wiped, so no axis is offered a reference check this "
                  "run: {}",
                  wiped.error().message);
    return std::nullopt;
  }
  // Axes that do not home (disabled) have nothing to trust: not logged.
  for (std::size_t a = 0; a < homing::kAxisCount; ++a)
    if ((*stored)[a] && homing::mode_homes(settings.axes[a].mode)) log_last_stop(a, *(*stored)[a], settings);
  return to_engine(*stored);
}

void keep_last_stops(persistence::SettingsStore& store, const StopReport& report) {
  if (auto r = store.record_last_stops(to_store(report.last_stops)); !r) {
    spdlog::error("last stops not kept: no axis will be offered a reference check at the next start: {}",
                  r.error().message);
  } else {
    int clean = 0;
    for (const homing::LastStop& s : report.last_stops) clean += s.clean ? 1 : 0;
    spdlog::info("last stops kept: {} axis(es) stopped cleanly", clean);
  }
  if (report.sim_carriages_mm)
    if (auto r = store.record_sim_carriages(*report.sim_carriages_mm); !r)
      spdlog::warn("simulator carriages not kept: {}", r.error().message);
}

persistence::SimCarriages kept_sim_carriages(persistence::SettingsStore& store) {
  auto kept = store.sim_carriages();
  if (!kept) {
    spdlog::warn("simulator carriages not read, they start where the simulator's defaults put them: {}",
                 kept.error().message);
    return {};
  }
  return *kept;
}

}  // namespace server
