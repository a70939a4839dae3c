#include "settings_check.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "gantry.hpp"
#include "motion.hpp"

namespace homing {
namespace {

std::optional<SettingsFault> fault(std::size_t axis, AxisField f, CheckRule r, double v = 0) {
  return SettingsFault{axis, f, r, v};
}

// Both speeds and the acceleration: every method that searches needs them.
std::optional<SettingsFault> check_speeds(const AxisSettings& s, std::size_t axis) {
  if (s.seek_feedrate_mm_per_min <= 0)
    return fault(axis, AxisField::seek_feedrate, CheckRule::not_positive, s.seek_feedrate_mm_per_min);
  if (s.latch_feedrate_mm_per_min <= 0)
    return fault(axis, AxisField::latch_feedrate, CheckRule::not_positive, s.latch_feedrate_mm_per_min);
  if (s.acceleration_mm_per_s2 <= 0)
    return fault(axis, AxisField::acceleration, CheckRule::not_positive, s.acceleration_mm_per_s2);
  return std::nullopt;
}

// Where the axis rests from its reference, and the move before its search.
std::optional<SettingsFault> check_pull_off_and_pre_move(const AxisSettings& s, std::size_t axis) {
  if (s.pull_off_mm < 0) return fault(axis, AxisField::pull_off, CheckRule::negative, s.pull_off_mm);
  if (s.pre_move_mode != PreMove::none && s.pre_move_distance_mm <= 0)
    return fault(axis, AxisField::pre_move_distance, CheckRule::missing_distance, s.pre_move_distance_mm);
  return std::nullopt;
}

std::optional<SettingsFault> check_motion(const AxisSettings& s, std::size_t axis) {
  if (auto f = check_speeds(s, axis)) return f;
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
  if (auto f = check_pull_off_and_pre_move(s, axis)) return f;
  const ModeRow& row = mode_row(s.mode);
  if (row.runs(Phase::push) && s.push_distance_mm <= 0)
    return fault(axis, AxisField::push_distance, CheckRule::missing_distance, s.push_distance_mm);
  if (row.runs(Phase::index) && s.index_pitch_mm <= 0)
    return fault(axis, AxisField::index_pitch, CheckRule::missing_distance, s.index_pitch_mm);
  if (const double needed = backoff_needed_mm(s); needed >= s.max_backoff_mm)
    return fault(axis, row.runs(Phase::push) ? AxisField::push_distance : AxisField::max_backoff,
                 CheckRule::backoff_too_short, needed);
  // A slave rests pull-off + compensation away from its edge.
  const double rest = s.pull_off_mm + (master_of(s) >= 0 ? s.switch_compensation_mm : 0.0);
  if (s.shared_limit && rest <= 0)
    return fault(axis, AxisField::pull_off, CheckRule::shared_limit_rests_on_sensor, rest);
  return std::nullopt;
}

// Hard-stop homing by the encoder: a limit the carriage's lag can pass only
// against the stop, and within the push's travel.
std::optional<SettingsFault> check_following_error(const AxisSettings& s, std::size_t axis) {
  if (!detects_stop_by_following_error(s)) return std::nullopt;
  const double limit = s.max_following_error_mm;
  if (limit <= 0) return fault(axis, AxisField::max_following_error, CheckRule::not_positive, limit);
  if (const double floor = following_error_floor_mm(s); limit <= floor)
    return fault(axis, AxisField::max_following_error, CheckRule::following_error_in_noise, floor);
  if (limit >= s.max_seek_travel_mm)
    return fault(axis, AxisField::max_following_error, CheckRule::following_error_beyond_travel, limit);
  return std::nullopt;
}

// Hard-stop homing: the push toward the stop at latch feedrate, bounded in
// travel and time, and the pull-off and pre-move at seek feedrate.
std::optional<SettingsFault> check_stop_search(const AxisSettings& s, std::size_t axis) {
  if (auto f = check_speeds(s, axis)) return f;
  if (s.max_seek_travel_mm <= 0)
    return fault(axis, AxisField::max_seek_travel, CheckRule::not_positive, s.max_seek_travel_mm);
  if (s.stall_timeout_ms <= 0)
    return fault(axis, AxisField::stall_timeout_ms, CheckRule::not_positive, s.stall_timeout_ms);
  if (auto f = check_following_error(s, axis)) return f;
  return check_pull_off_and_pre_move(s, axis);
}

std::optional<SettingsFault> check_limits(const AxisSettings& s, std::size_t axis) {
  if (!s.soft_limits_enable) return std::nullopt;
  if (s.soft_limit_min_mm >= s.soft_limit_max_mm)
    return fault(axis, AxisField::soft_limit_max, CheckRule::soft_limits_inverted, s.soft_limit_max_mm);
  auto outside = [&](double x) { return x < s.soft_limit_min_mm || x > s.soft_limit_max_mm; };
  // home_position is a place on the axis, except for an absolute encoder (its offset).
  const Coordinate c = mode_row(s.mode).coordinate;
  const bool home_is_a_place = c == Coordinate::here || c == Coordinate::reference_edge ||
                               c == Coordinate::mechanical_stop || c == Coordinate::drive_reference;
  if (home_is_a_place && outside(s.home_position_mm))
    return fault(axis, AxisField::home_position, CheckRule::outside_soft_limits, s.home_position_mm);
  if (final_move_wanted(s) && outside(s.final_position_mm))
    return fault(axis, AxisField::final_position, CheckRule::outside_soft_limits, s.final_position_mm);
  return std::nullopt;
}

// The rules of a gantry pair, checked on the slave. `pair` holds the settings
// both axes move with (motion_settings).
std::optional<SettingsFault> check_slave(const Settings& settings, const Settings& pair, std::size_t axis) {
  const AxisSettings& s = settings.axes[axis];
  const int m = master_of(s);
  if (m < 0) return std::nullopt;
  if (m == static_cast<int>(axis) || m >= static_cast<int>(kAxisCount))
    return fault(axis, AxisField::slave_of, CheckRule::slave_invalid, s.slave_of);
  if (!mode_homes(s.mode))
    return fault(axis, AxisField::mode, CheckRule::disabled_in_gantry, s.slave_of);
  const AxisSettings& master = settings.axes[static_cast<std::size_t>(m)];
  if (!mode_homes(master.mode))
    return fault(axis, AxisField::slave_of, CheckRule::disabled_in_gantry, s.slave_of);
  if (master_of(master) >= 0)
    return fault(axis, AxisField::slave_of, CheckRule::slave_of_slave, s.slave_of);
  // A master squares on its sensor: a mode without one is no master at all.
  if (!mode_row(master.mode).needs_signal(Signal::home_sensor))
    return fault(axis, AxisField::slave_of, CheckRule::slave_invalid, s.slave_of);
  for (std::size_t other = 0; other < axis; ++other)  // one slave per master
    if (master_of(settings.axes[other]) == m)
      return fault(axis, AxisField::slave_of, CheckRule::slave_invalid, s.slave_of);
  if (!mode_row(s.mode).gantry_slave)
    return fault(axis, AxisField::mode, CheckRule::slave_needs_sensor, static_cast<double>(s.mode));
  // Pushing into the stops makes the motors lose steps by different amounts
  // with no sensor watching: the pair would rack unseen. A gantry squares on
  // its two sensors instead (pushing modes are for one axis with two drives
  // on one output, the hardware-slaved gantry).
  if (!mode_row(master.mode).gantry_master)
    return fault(axis, AxisField::slave_of, CheckRule::commutator_needs_switch_master, s.slave_of);
  if (s.max_misalignment_mm <= 0)
    return fault(axis, AxisField::max_misalignment, CheckRule::not_positive, s.max_misalignment_mm);
  const AxisSettings& moves = pair.axes[axis];
  if (const double stop = gantry_stop_distance_mm(moves); stop >= s.max_misalignment_mm)
    return fault(axis, AxisField::max_misalignment, CheckRule::gantry_stop_too_long, stop);
  // The squaring moves the slave against its master by its sensor's skew plus
  // this; alone it must leave room for a skew.
  const double built_in = moves.pull_off_mm + s.switch_compensation_mm -
                          pair.axes[static_cast<std::size_t>(m)].pull_off_mm;
  if (std::abs(built_in) >= s.max_misalignment_mm)
    return fault(axis, AxisField::switch_compensation, CheckRule::squaring_beyond_misalignment, built_in);
  return std::nullopt;
}

// A locking indexer holds one axis: a gantry side held while its partner
// moves would rack the pair, so neither side of a gantry may have one.
std::optional<SettingsFault> check_indexer(const Settings& settings, std::size_t axis) {
  const AxisSettings& s = settings.axes[axis];
  if (!s.indexer_lock) return std::nullopt;
  bool gantry = master_of(s) >= 0;
  for (std::size_t other = 0; other < kAxisCount; ++other)
    gantry = gantry || (other != axis && master_of(settings.axes[other]) == static_cast<int>(axis));
  if (gantry) return fault(axis, AxisField::indexer_lock, CheckRule::indexer_in_gantry, 1);
  if (s.lock_timeout_ms <= 0)
    return fault(axis, AxisField::lock_timeout_ms, CheckRule::not_positive, s.lock_timeout_ms);
  return std::nullopt;
}

// End-of-travel limit switches: the axis must come to rest before the
// mechanical stop beyond them; home_cam cannot search without them.
std::optional<SettingsFault> check_limit_switches(const AxisSettings& s, std::size_t axis) {
  if (mode_row(s.mode).runs(Phase::limit_reversal) && !s.limits_fitted)
    return fault(axis, AxisField::limits_fitted, CheckRule::cam_needs_limits, 0);
  if (!s.limits_fitted) return std::nullopt;
  if (const double needed = limit_stop_distance_mm(s); needed >= s.limit_overtravel_mm)
    return fault(axis, AxisField::limit_overtravel, CheckRule::limit_overtravel_too_short, needed);
  return std::nullopt;
}

std::optional<SettingsFault> check_axis_in(const Settings& settings, const Settings& pair, std::size_t axis) {
  // Checked on the axis's own setting, whatever it moves with: a rotary X
  // is wrong even while X is a slave.
  if (settings.axes[axis].kind == AxisKind::rotary && !may_be_rotary(axis))
    return fault(axis, AxisField::kind, CheckRule::kind_linear_only, static_cast<double>(AxisKind::rotary));
  if (auto f = check_slave(settings, pair, axis)) return f;
  if (auto f = check_indexer(settings, axis)) return f;
  const AxisSettings& s = pair.axes[axis];
  if (auto f = check_limits(s, axis)) return f;
  const ModeRow& row = mode_row(s.mode);
  if (s.shared_limit && !row.shares_limit)
    return fault(axis, AxisField::shared_limit, CheckRule::shared_limit_without_sensor, 1);
  if (auto f = check_limit_switches(s, axis)) return f;
  if (row.runs(Phase::seek) || row.runs(Phase::cam_seek)) return check_motion(s, axis);
  if (row.runs(Phase::push_to_stop)) return check_stop_search(s, axis);
  if (row.runs(Phase::drive_homing) && !(s.drive_home_timeout_s > 0))
    return fault(axis, AxisField::drive_home_timeout, CheckRule::missing_time_limit, s.drive_home_timeout_s);
  if (final_move_wanted(s)) {
    if (s.seek_feedrate_mm_per_min <= 0)
      return fault(axis, AxisField::seek_feedrate, CheckRule::not_positive, s.seek_feedrate_mm_per_min);
    if (s.acceleration_mm_per_s2 <= 0)
      return fault(axis, AxisField::acceleration, CheckRule::not_positive, s.acceleration_mm_per_s2);
  }
  return std::nullopt;
}

}  // namespace

double seek_stop_distance_mm(const AxisSettings& s) {
  const double v = mm_per_min_to_mm_per_s(s.seek_feedrate_mm_per_min);
  return stop_distance_mm(v, s.acceleration_mm_per_s2) + v * s.debounce_ms / 1000.0;
}

double backoff_needed_mm(const AxisSettings& s) {
  return seek_stop_distance_mm(s) + (mode_row(s.mode).runs(Phase::push) ? s.push_distance_mm : 0.0);
}

double gantry_stop_distance_mm(const AxisSettings& s) {
  const double v = mm_per_min_to_mm_per_s(std::max(s.seek_feedrate_mm_per_min, s.jog_feedrate_mm_per_min));
  return stop_distance_mm(v, s.acceleration_mm_per_s2);
}

double limit_stop_distance_mm(const AxisSettings& s) {
  const double v = mm_per_min_to_mm_per_s(std::max(s.seek_feedrate_mm_per_min, s.jog_feedrate_mm_per_min));
  return stop_distance_mm(v, s.acceleration_mm_per_s2) + v * kBrakingHorizon_s;
}

double following_error_floor_mm(const AxisSettings& s) {
  return 10 * kEncoderReadingError_mm + mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min) * kBrakingHorizon_s;
}

bool final_move_wanted(const AxisSettings& s) {
  switch (mode_row(s.mode).final_move) {
    case FinalMove::never: return false;
    case FinalMove::if_enabled: return s.final_move_enable;
    case FinalMove::always: return true;
  }
  return false;
}

double index_search_mm(const AxisSettings& s) {
  return s.index_pitch_mm * 1.1 +
         stop_distance_mm(mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min), s.acceleration_mm_per_s2);
}

std::optional<SettingsFault> check_axis(const Settings& settings, std::size_t axis) {
  return check_axis_in(settings, motion_settings(settings), axis);
}

SettingsFaults check_settings(const Settings& settings) {
  const Settings pair = motion_settings(settings);
  SettingsFaults out{};
  for (std::size_t a = 0; a < kAxisCount; ++a) out[a] = check_axis_in(settings, pair, a);
  return out;
}

std::optional<SettingsFault> new_fault(const Settings& before, const Settings& after) {
  const SettingsFaults old = check_settings(before);
  const SettingsFaults now = check_settings(after);
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    if (!now[a]) continue;
    const bool same = old[a] && old[a]->field == now[a]->field && old[a]->rule == now[a]->rule;
    if (!same) return now[a];
  }
  return std::nullopt;
}

std::string describe_fault(const SettingsFault& f, const Settings& settings) {
  const AxisSettings& s = settings.axes[f.axis];
  const auto letter = kAxisLetters[f.axis];
  const auto unit = axis_unit(settings, f.axis);  // a slave's is its master's
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
      return fmt::format("{} = {:g}: the master of a gantry must home on a switch edge, not in a pushing "
                         "mode (pushing into the stops makes the two motors lose steps unwatched and racks "
                         "the gantry; the pair squares on its two sensors; pushing modes are for one axis "
                         "with two drives on one output)", name, f.value);
    case CheckRule::soft_limits_inverted:
      return fmt::format("axis.{}.soft_limit_min ({:g}) must be below soft_limit_max ({:g})", letter,
                         s.soft_limit_min_mm, s.soft_limit_max_mm);
    case CheckRule::outside_soft_limits:
      return fmt::format("{} = {:g} {} lies outside the soft limits [{:g}, {:g}]", name, f.value, unit,
                         s.soft_limit_min_mm, s.soft_limit_max_mm);
    case CheckRule::disabled_in_gantry:
      return fmt::format("{}: a disabled axis can be neither master nor slave of a gantry; set "
                         "axis.{}.slave_of = 0 first, or give both axes a homing mode", name, letter);
    case CheckRule::slave_of_slave:
      return fmt::format("{} = {:g} names an axis that is itself a slave; a slave's master must be "
                         "an axis that is no slave", name, f.value);
    case CheckRule::gantry_stop_too_long:
      return fmt::format("the gantry needs {:.3f} {} to stop from its fastest speed (seek or jog "
                         "feedrate, at the lower acceleration of the pair), not less than {} = {:g} {}; "
                         "one side stalled by a drive fault would rack it: lower the master's "
                         "feedrates, raise the accelerations or raise max_misalignment",
                         f.value, unit, name, s.max_misalignment_mm, unit);
    case CheckRule::squaring_beyond_misalignment:
      return fmt::format("{} plus the slave's pull-off minus the master's is {:g} {}, not less than "
                         "axis.{}.max_misalignment = {:g} {}: every homing would end in a misalignment alarm",
                         name, f.value, unit, letter, s.max_misalignment_mm, unit);
    case CheckRule::backoff_too_short:
      return fmt::format("axis.{}.max_backoff = {:g} {} cannot release the sensor: the axis may come to "
                         "rest {:.3f} {} past the trigger (stop distance{}); raise max_backoff{}",
                         letter, s.max_backoff_mm, unit, f.value, unit,
                         mode_is_pushing(s.mode) ? " plus push_distance" : "",
                         mode_is_pushing(s.mode) ? " or lower push_distance" : "");
    case CheckRule::shared_limit_without_sensor:
      return fmt::format("{}: mode {} homes without a home sensor, so there is none to share with a hard "
                         "limit; set {} = 0", name, mode_name(s.mode), name);
    case CheckRule::indexer_in_gantry:
      return fmt::format("{}: a locking indexer holds one axis; on a gantry one side would be held while the "
                         "other moves; switch indexer_lock off or take the axis out of the gantry (slave_of)",
                         name);
    case CheckRule::cam_needs_limits:
      return fmt::format("axis.{}.mode = {}: the search reverses at the end-of-travel limit switches; set "
                         "{} = 1 and wire limit_min and limit_max", letter, mode_name(s.mode), name);
    case CheckRule::limit_overtravel_too_short:
      return fmt::format("stopping from {:g} {}/min (the faster of seek_feedrate and jog_feedrate) at acceleration "
                         "{:g} {}/s² after a limit switch trips takes {:.3f} {} (one 20 ms period included), not "
                         "less than {} = {:g} {}: the axis would reach the mechanical stop; lower the feedrates, "
                         "raise acceleration or measure the overtravel again",
                         std::max(s.seek_feedrate_mm_per_min, s.jog_feedrate_mm_per_min), unit,
                         s.acceleration_mm_per_s2, unit, f.value, unit, name, s.limit_overtravel_mm, unit);
    case CheckRule::following_error_in_noise:
      return fmt::format("{} = {:g} {} does not exceed {:.3f} {}: the encoder's resolution and noise ({:g} {} a "
                         "reading, ten readings' worth) plus the travel at latch_feedrate {:g} {}/min in one 20 ms "
                         "control period, which a moving axis lags anyway; the stop would be found in free air. "
                         "Raise {} or lower latch_feedrate",
                         name, s.max_following_error_mm, unit, f.value, unit, kEncoderReadingError_mm, unit,
                         s.latch_feedrate_mm_per_min, unit, name);
    case CheckRule::following_error_beyond_travel:
      return fmt::format("{} = {:g} {} is not shorter than axis.{}.max_seek_travel = {:g} {}: the push ends before "
                         "the carriage could fall that far behind its steps, so the stop is never told; lower {} "
                         "(a stalled carriage is told at once) or raise max_seek_travel",
                         name, f.value, unit, letter, s.max_seek_travel_mm, unit, name);
    case CheckRule::shared_limit_rests_on_sensor:
      return fmt::format("{}: the axis would rest {:g} {} from its edge (pull-off, plus a slave's "
                         "switch_compensation); a shared home/limit sensor needs more than 0 so the axis "
                         "comes to rest off its sensor", name, f.value, unit);
    case CheckRule::kind_linear_only:
      return fmt::format("{} = rotary: {} is a linear axis (mm); only A, B and C can be rotary. Set {} = "
                         "linear, or put the rotary axis on A, B or C",
                         name, kAxisUpper[f.axis], name);
    case CheckRule::missing_time_limit:
      return fmt::format("{} is {:g} s; mode {} waits for the drive's home done at most this long and needs "
                         "it greater than 0 (longer than the drive's own homing takes)", name, f.value,
                         mode_name(s.mode));
  }
  return "?";
}

}  // namespace homing
