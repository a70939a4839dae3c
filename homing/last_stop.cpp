#include "last_stop.hpp"

#include "gantry.hpp"

namespace homing {

LastStops last_stops_at_shutdown(const Settings& settings, const Status& status, const Outputs& outputs) {
  // The frame an axis is homed in is that of the settings it moves with (a slave's master's).
  const Settings motion = motion_settings(settings);
  const bool alarm = status.alarm || status.global_alarm != AlarmCode::none;
  LastStops stops{};
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    const AxisStatus& x = status.axes[a];
    LastStop& stop = stops[a];
    stop.position_mm = x.position_mm;
    stop.frame = home_frame(motion.axes[a]);
    const bool homed = x.trust == Trust::homed_this_power_on || x.trust == Trust::reference_checked;
    const bool at_rest = x.velocity_mm_per_s == 0 && !x.busy;
    stop.clean = homed && at_rest && !alarm && outputs.axes[a].enable;
  }
  return stops;
}

}  // namespace homing
