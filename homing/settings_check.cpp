#include "settings_check.hpp"

#include <fmt/format.h>

#include "motion.hpp"

namespace homing {
namespace {

std::optional<SettingsFault> fault(std::size_t axis, AxisField f, CheckRule r, double v = 0) {
  return SettingsFault{axis, f, r, v};
}

std::optional<SettingsFault> check_motion(const AxisSettings& s, std::size_t axis) {
  if (s.seek_feedrate_mm_per_min <= 0)
    return fault(axis, AxisField::seek_feedrate, CheckRule::not_positive, s.seek_feedrate_mm_per_min);
  if (s.latch_feedrate_mm_per_min <= 0)
    return fault(axis, AxisField::latch_feedrate, CheckRule::not_positive, s.latch_feedrate_mm_per_min);
  if (s.acceleration_mm_per_s2 <= 0)
    return fault(axis, AxisField::acceleration, CheckRule::not_positive, s.acceleration_mm_per_s2);
  if (s.latch_feedrate_mm_per_min >= s.seek_feedrate_mm_per_min)
    return fault(axis, AxisField::latch_feedrate, CheckRule::latch_not_slower, s.latch_feedrate_mm_per_min);
  if (s.max_seek_travel_mm <= 0)
    return fault(axis, AxisField::max_seek_travel, CheckRule::not_positive, s.max_seek_travel_mm);
  if (s.max_stop_distance_mm <= 0)
    return fault(axis, AxisField::max_stop_distance, CheckRule::not_positive, s.max_stop_distance_mm);
  if (s.max_backoff_mm <= 0)
    return fault(axis, AxisField::max_backoff, CheckRule::not_positive, s.max_backoff_mm);
  if (const double needed = seek_stop_distance_mm(s); needed > s.max_stop_distance_mm)
    return fault(axis, AxisField::max_stop_distance, CheckRule::stop_distance_too_long, needed);
  if (s.pull_off_mm < 0) return fault(axis, AxisField::pull_off, CheckRule::negative, s.pull_off_mm);
  if (s.pre_move_mode != PreMove::none && s.pre_move_distance_mm <= 0)
    return fault(axis, AxisField::pre_move_distance, CheckRule::missing_distance, s.pre_move_distance_mm);
  if (mode_is_pushing(s.mode) && s.push_distance_mm <= 0)
    return fault(axis, AxisField::push_distance, CheckRule::missing_distance, s.push_distance_mm);
  if (s.mode == HomingMode::switch_index && s.index_pitch_mm <= 0)
    return fault(axis, AxisField::index_pitch, CheckRule::missing_distance, s.index_pitch_mm);
  return std::nullopt;
}

std::optional<SettingsFault> check_limits(const AxisSettings& s, std::size_t axis) {
  if (!s.soft_limits_enable) return std::nullopt;
  if (s.soft_limit_min_mm >= s.soft_limit_max_mm)
    return fault(axis, AxisField::soft_limit_max, CheckRule::soft_limits_inverted, s.soft_limit_max_mm);
  auto outside = [&](double x) { return x < s.soft_limit_min_mm || x > s.soft_limit_max_mm; };
  if (s.mode != HomingMode::disabled && outside(s.home_position_mm) && !mode_is_absolute(s.mode))
    return fault(axis, AxisField::home_position, CheckRule::outside_soft_limits, s.home_position_mm);
  const bool final_move = s.mode == HomingMode::absolute_final ||
                          (s.final_move_enable && s.mode != HomingMode::absolute &&
                           s.mode != HomingMode::disabled);
  if (final_move && outside(s.final_position_mm))
    return fault(axis, AxisField::final_position, CheckRule::outside_soft_limits, s.final_position_mm);
  return std::nullopt;
}

std::optional<SettingsFault> check_slave(const Settings& settings, std::size_t axis) {
  const AxisSettings& s = settings.axes[axis];
  const int m = master_of(s);
  if (m < 0) return std::nullopt;
  if (m == static_cast<int>(axis) || m >= static_cast<int>(kAxisCount))
    return fault(axis, AxisField::slave_of, CheckRule::slave_invalid, s.slave_of);
  const AxisSettings& master = settings.axes[static_cast<std::size_t>(m)];
  if (master_of(master) >= 0 || !mode_uses_switch(master.mode))
    return fault(axis, AxisField::slave_of, CheckRule::slave_invalid, s.slave_of);
  for (std::size_t other = 0; other < axis; ++other)  // one slave per master
    if (master_of(settings.axes[other]) == m)
      return fault(axis, AxisField::slave_of, CheckRule::slave_invalid, s.slave_of);
  if (s.slave_mode == SlaveMode::own_output && !mode_uses_switch(s.mode))
    return fault(axis, AxisField::mode, CheckRule::slave_needs_sensor, static_cast<double>(s.mode));
  if (s.max_misalignment_mm <= 0)
    return fault(axis, AxisField::max_misalignment, CheckRule::not_positive, s.max_misalignment_mm);
  return std::nullopt;
}

}  // namespace

double seek_stop_distance_mm(const AxisSettings& s) {
  const double v = mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min);
  return stop_distance_mm(v, s.acceleration_mm_per_s2) + v * s.debounce_ms / 1000.0;
}

std::optional<SettingsFault> check_axis(const Settings& settings, std::size_t axis) {
  const AxisSettings& s = settings.axes[axis];
  if (auto f = check_slave(settings, axis)) return f;
  if (auto f = check_limits(s, axis)) return f;
  const bool slave = master_of(s) >= 0;
  // A commutator slave moves with its master's homing settings; its own
  // motion settings are not used for homing.
  if (slave && s.slave_mode == SlaveMode::external_commutator) return std::nullopt;
  if (mode_uses_switch(s.mode)) return check_motion(s, axis);
  if (s.mode == HomingMode::absolute_final || (s.final_move_enable && s.mode == HomingMode::manual)) {
    if (s.seek_feedrate_mm_per_min <= 0)
      return fault(axis, AxisField::seek_feedrate, CheckRule::not_positive, s.seek_feedrate_mm_per_min);
    if (s.acceleration_mm_per_s2 <= 0)
      return fault(axis, AxisField::acceleration, CheckRule::not_positive, s.acceleration_mm_per_s2);
  }
  return std::nullopt;
}

std::string describe_fault(const SettingsFault& f, const Settings& settings) {
  const AxisSettings& s = settings.axes[f.axis];
  const auto letter = kAxisLetters[f.axis];
  const auto unit = axis_unit(f.axis);
  const std::string name = fmt::format("axis.{}.{}", letter, field_name(f.field));
  switch (f.rule) {
    case CheckRule::none: return "";
    case CheckRule::not_positive:
      return fmt::format("{} is {:g}; it must be greater than 0", name, f.value);
    case CheckRule::latch_not_slower:
      return fmt::format("{} ({:g} {}/min) must be slower than seek_feedrate ({:g} {}/min)", name,
                         s.latch_feedrate_mm_per_min, unit, s.seek_feedrate_mm_per_min, unit);
    case CheckRule::stop_distance_too_long:
      return fmt::format(
          "stopping from seek_feedrate {:g} {}/min at acceleration {:g} {}/s² takes {:.3f} {}, more "
          "than {} = {:g} {}; lower seek_feedrate, raise acceleration or raise max_stop_distance",
          s.seek_feedrate_mm_per_min, unit, s.acceleration_mm_per_s2, unit, f.value, unit, name,
          s.max_stop_distance_mm, unit);
    case CheckRule::negative:
      return fmt::format("{} is {:g}; it must not be negative", name, f.value);
    case CheckRule::missing_distance:
      return fmt::format("{} is {:g}; mode {} needs it greater than 0", name, f.value,
                         mode_name(s.mode));
    case CheckRule::slave_invalid:
      return fmt::format("{} = {:g} names no axis that can be a master (itself, a slave, or an "
                         "axis whose mode has no home sensor)", name, f.value);
    case CheckRule::slave_needs_sensor:
      return fmt::format("{} is a software-slaved axis in mode {}: it needs its own home sensor "
                         "(a switch or pushing mode)", kAxisUpper[f.axis], mode_name(s.mode));
    case CheckRule::commutator_needs_switch_master:
      return fmt::format("{}: the master of an external-commutator slave must home on a switch", name);
    case CheckRule::soft_limits_inverted:
      return fmt::format("axis.{}.soft_limit_min ({:g}) must be below soft_limit_max ({:g})", letter,
                         s.soft_limit_min_mm, s.soft_limit_max_mm);
    case CheckRule::outside_soft_limits:
      return fmt::format("{} = {:g} {} lies outside the soft limits [{:g}, {:g}]", name, f.value, unit,
                         s.soft_limit_min_mm, s.soft_limit_max_mm);
  }
  return "?";
}

}  // namespace homing
