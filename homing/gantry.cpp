#include "gantry.hpp"

#include <algorithm>

#include "mutation.hpp"

namespace homing {

int gantry_master(const Settings& settings, std::size_t axis) {
  const AxisSettings& s = settings.axes[axis];
  const int m = master_of(s);
  if (m < 0 || m >= static_cast<int>(kAxisCount) || m == static_cast<int>(axis)) return -1;
  const AxisSettings& master = settings.axes[static_cast<std::size_t>(m)];
  // A pushing master still pairs here; the rule set refuses it (check_slave).
  if (!mode_row(s.mode).gantry_slave) return -1;
  if (master_of(master) >= 0 || !mode_row(master.mode).needs_signal(Signal::home_sensor)) return -1;
  for (std::size_t other = 0; other < axis; ++other)  // one slave per master: the first
    if (master_of(settings.axes[other]) == m) return -1;
  return m;
}

int gantry_slave(const Settings& settings, std::size_t axis) {
  for (std::size_t s = 0; s < kAxisCount; ++s)
    if (gantry_master(settings, s) == static_cast<int>(axis)) return static_cast<int>(s);
  return -1;
}

int gantry_partner(const Settings& settings, std::size_t axis) {
  const int m = gantry_master(settings, axis);
  return m >= 0 ? m : gantry_slave(settings, axis);
}

bool is_commutator_slave(const Settings& settings, std::size_t axis) {
  return gantry_master(settings, axis) >= 0 &&
         settings.axes[axis].slave_mode == SlaveMode::external_commutator;
}

Settings motion_settings(const Settings& settings) {
  Settings out = settings;
  for (std::size_t s = 0; s < kAxisCount; ++s) {
    const int m = gantry_master(settings, s);
    if (m < 0) continue;
    const AxisSettings& own = settings.axes[s];
    AxisSettings& master = out.axes[static_cast<std::size_t>(m)];
    AxisSettings& slave = out.axes[s];
    slave = settings.axes[static_cast<std::size_t>(m)];
    slave.sensor_nc = own.sensor_nc;
    slave.debounce_ms = own.debounce_ms;
    slave.shared_limit = own.shared_limit;
    if (own.slave_mode == SlaveMode::own_output) slave.pull_off_mm = own.pull_off_mm;
    slave.switch_compensation_mm = own.switch_compensation_mm;
    slave.max_misalignment_mm = own.max_misalignment_mm;
    slave.slave_of = own.slave_of;
    slave.slave_mode = own.slave_mode;
    slave.indexer_lock = own.indexer_lock;  // an indexer is the slave's own hardware
    slave.lock_timeout_ms = own.lock_timeout_ms;
    slave.limits_fitted = own.limits_fitted;  // limit switches at the slave carriage's own ends
    slave.limits_nc = own.limits_nc;
    slave.limit_overtravel_mm = own.limit_overtravel_mm;
    if (planted(Mutant::slave_keeps_own_direction)) slave.direction = own.direction;
    const double pair_accel = std::min(own.acceleration_mm_per_s2, master.acceleration_mm_per_s2);
    slave.acceleration_mm_per_s2 = master.acceleration_mm_per_s2 = pair_accel;
  }
  return out;
}

bool inherited_from_master(AxisField field, SlaveMode mode) {
  switch (field) {
    case AxisField::none:
    case AxisField::mode:
    case AxisField::sensor_nc:
    case AxisField::debounce_ms:
    case AxisField::shared_limit:
    case AxisField::switch_compensation:
    case AxisField::max_misalignment:
    case AxisField::slave_of:
    case AxisField::slave_mode:
    case AxisField::indexer_lock:
    case AxisField::lock_timeout_ms:
    case AxisField::limits_fitted:
    case AxisField::limits_nc:
    case AxisField::limit_overtravel:
    case AxisField::acceleration:
    case AxisField::max_skew_change:
    case AxisField::refcheck_tolerance: return false;
    case AxisField::pull_off: return mode == SlaveMode::external_commutator;
    default: return true;
  }
}

// Any axis slave_of names, not only the master of a valid pair: a fault that
// refuses the pair is about a slave already, in its master's unit.
AxisKind axis_kind(const Settings& settings, std::size_t axis) {
  const int m = master_of(settings.axes[axis]);
  const bool names_master = m >= 0 && m < static_cast<int>(kAxisCount) && m != static_cast<int>(axis);
  return settings.axes[names_master ? static_cast<std::size_t>(m) : axis].kind;
}

std::string_view axis_unit(const Settings& settings, std::size_t axis) {
  return unit_of(axis_kind(settings, axis));
}

AxisSettings commutator_slave_homing(AxisSettings s) {
  s.max_seek_travel_mm = s.max_misalignment_mm;
  s.pre_move_mode = PreMove::none;
  s.final_move_enable = false;
  // On its own switch edge: the edge of its master's method, without push or index.
  const ModeRow& row = mode_row(s.mode);
  if (row.runs(Phase::push) || row.runs(Phase::index))
    s.mode = row.runs(Phase::reapproach) ? HomingMode::switch_reapproach : HomingMode::switch_release;
  s.seek_feedrate_mm_per_min = s.latch_feedrate_mm_per_min;
  return s;
}

}  // namespace homing
