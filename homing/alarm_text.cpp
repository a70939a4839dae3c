// Alarm texts: what happened, where, with the figures; then what to check,
// from the alarm table (alarms.hpp), the same words an HMI's alarm list shows.
#include <fmt/format.h>

#include <cmath>

#include "alarms.hpp"
#include "gantry.hpp"
#include "health.hpp"
#include "settings_check.hpp"

namespace homing {
namespace {

// Hard-stop homing by the encoder: the stall is its following error.
std::string following_error_note(const AxisSettings& s, std::string_view unit) {
  if (!detects_stop_by_following_error(s)) return "";
  return fmt::format(": the carriage never fell behind its steps by more than max_following_error {:g} {}",
                     s.max_following_error_mm, unit);
}

// A gantry's racking: which side carried it out, how far from square, and
// whether the cycle found it out of square already.
std::string misalignment_text(std::size_t axis, const Alarm& a, const Settings& settings) {
  const char X = kAxisUpper[axis];
  const auto u = axis_unit(settings, axis);
  const int mi = gantry_master(settings, axis);
  std::string who;
  if (a.side != GantrySide::none && mi >= 0) {
    const bool master = is_master_side(a.side);
    const char side = kAxisUpper[master ? static_cast<std::size_t>(mi) : axis];
    const char other = kAxisUpper[master ? axis : static_cast<std::size_t>(mi)];
    const bool found = a.side == GantrySide::master_sensor_far || a.side == GantrySide::slave_sensor_far;
    who = found ? fmt::format(": {} ({}) found its home sensor too far from {}'s", side, master ? "master" : "slave",
                              other)
                : fmt::format(": {} ({}) did not find its home sensor", side, master ? "master" : "slave");
  }
  const std::string start =
      std::abs(a.rack_at_start_mm) < 0.0005
          ? std::string{"the pair started the cycle square"}
          : fmt::format("the pair started the cycle {:.3f} {} out of square (an earlier stop left it racked)",
                        a.rack_at_start_mm, u);
  return fmt::format("{}: gantry stopped during {}{}, before racking by {:.3f} {} from square, more than "
                     "max_misalignment {:g} {}; {}",
                     X, phase_name(a.phase), who, a.value, u, settings.axes[axis].max_misalignment_mm, u, start);
}

// What happened, with the axis letter and the figures.
std::string what_happened(std::size_t axis, const Alarm& a, const Settings& settings) {
  // Figures from the settings the axis moves with (a slave its master's).
  const Settings moves = motion_settings(settings);
  const AxisSettings& s = moves.axes[axis];
  const char X = kAxisUpper[axis];
  const auto u = axis_unit(settings, axis);  // a slave's is its master's
  const auto ph = phase_name(a.phase);
  switch (a.code) {
    case AlarmCode::none: return "";
    case AlarmCode::sensor_not_found:
      return fmt::format("{}: home sensor not found within {:g} {} of travel", X, s.max_seek_travel_mm, u);
    case AlarmCode::overrun_during_stop:
      // Unfiltered, a bouncing contact opens for a moment as a short cam ends:
      // the technician should not be sent to rebuild a cam that is fine.
      return fmt::format("{}: home sensor released {:.3f} {} after the trigger, while stopping; the trigger is "
                         "shorter than the stop distance ({:.3f} {}){}",
                         X, a.value, u, seek_stop_distance_mm(s), u,
                         s.debounce_ms > 0 ? ""
                                           : fmt::format(", or the contact bounced (axis.{}.debounce_ms is 0: a "
                                                         "bounce reads as a release)",
                                                         static_cast<char>(kAxisUpper[axis] - 'A' + 'a')));
    case AlarmCode::stop_distance_exceeded:
      return fmt::format("{}: came to rest {:.3f} {} past the trigger, more than max_stop_distance "
                         "{:g} {}", X, a.value, u, s.max_stop_distance_mm, u);
    case AlarmCode::not_released:
      if (a.phase == Phase::assign)
        return fmt::format("{}: shared home/limit sensor still active after the pull-off of {:g} {}", X,
                           s.pull_off_mm, u);
      if (a.phase == Phase::measure_travel)
        return fmt::format("{}: the far limit switch the measurement found still active after backing off {:g} {} "
                           "(check it and limits_nc)", X, s.max_backoff_mm, u);
      return fmt::format("{}: home sensor still active after backing off {:g} {} (phase {})", X,
                         s.max_backoff_mm, u, ph);
    case AlarmCode::index_not_found:
      return fmt::format("{}: no encoder index pulse within {:.3f} {} after the switch edge", X, a.value, u);
    case AlarmCode::slave_sensor_missing:
      return fmt::format("{}: software-slaved axis has no home sensor of its own (mode {})", X,
                         mode_name(s.mode));
    case AlarmCode::misalignment: return misalignment_text(axis, a, settings);
    case AlarmCode::hard_limit:
      return fmt::format("{}: shared home/limit sensor tripped at {:.3f} {} after homing", X, a.value, u);
    case AlarmCode::soft_limit:
      return fmt::format("{}: position {:.3f} {} beyond the soft limits [{:g}, {:g}]", X, a.value, u,
                         s.soft_limit_min_mm, s.soft_limit_max_mm);
    case AlarmCode::aborted:
      return fmt::format("{}: homing aborted by command during {}", X, ph);
    case AlarmCode::emergency_stop:
      return fmt::format("{}: emergency stop during {}", X, ph);
    case AlarmCode::drive_fault:
      return fmt::format("{}: drive fault during {}", X, ph);
    case AlarmCode::settings_fault: {
      SettingsFault f{axis, a.field, static_cast<CheckRule>(a.rule), a.value};
      return fmt::format("{}: settings fault, homing refused before any motion: {}", X,
                         describe_fault(f, settings));
    }
    case AlarmCode::communication_lost:
      return fmt::format("{}: communication lost: host.heartbeat did not change for {} ms during {}", X,
                         settings.global.watchdog_ms, ph);
    case AlarmCode::settings_lost:
      return "settings lost: the settings database was unreadable and defaults were loaded";
    case AlarmCode::reapproach_not_found:
      return fmt::format("{}: home sensor not found again within {:g} {} while re-approaching", X,
                         s.max_backoff_mm, u);
    case AlarmCode::permit_withdrawn:
      return fmt::format("{}: homing permit went off during {}", X, ph);
    case AlarmCode::encoder_fault:
      return fmt::format("{}: absolute encoder gives no valid position", X);
    case AlarmCode::stop_not_found:
      return fmt::format("{}: no stall reported within {:.3f} {} of travel toward the mechanical stop "
                         "(max_seek_travel {:g} {}){}", X, a.value, u, s.max_seek_travel_mm, u,
                         following_error_note(s, u));
    case AlarmCode::stall_timeout:
      return fmt::format("{}: no stall reported after pushing toward the mechanical stop for {:.1f} s "
                         "(stall_timeout_ms {:g}){}", X, a.value, s.stall_timeout_ms, following_error_note(s, u));
    case AlarmCode::stall_at_start:
      return fmt::format("{}: the drive's stall input was active before the push toward the stop began", X);
    case AlarmCode::drive_no_answer:
      return fmt::format("{}: the drive did not report home done within {:g} s of the home request", X,
                         s.drive_home_timeout_s);
    case AlarmCode::drive_answered_at_once:
      return fmt::format("{}: the drive reported home done {:.3f} s after the home request, sooner than any "
                         "homing ({:g} s): it did not home", X, a.value, kDriveMinHomingTime_s);
    case AlarmCode::drive_reference_lost:
      return fmt::format("{}: the drive's home done went off at {:.3f} {} while the axis was homed", X, a.value, u);
    case AlarmCode::unlock_not_confirmed:
      return fmt::format("{}: locking indexer not reported unlocked within lock_timeout_ms {:g} ms of the "
                         "unlock output; the axis did not move", X, s.lock_timeout_ms);
    case AlarmCode::lock_not_confirmed:
      return fmt::format("{}: locking indexer not reported locked within lock_timeout_ms {:g} ms after the "
                         "axis came to rest", X, s.lock_timeout_ms);
    case AlarmCode::lock_engaged:
      return fmt::format("{}: locking indexer reported locked during {} while the unlock output was on", X, ph);
    case AlarmCode::cam_not_found:
      return fmt::format("{}: home cam not found: the search reversed at one limit switch and met the other "
                         "at {:.3f} {} without passing the cam", X, a.value, u);
    case AlarmCode::limit_in_homing:
      if (a.phase == Phase::return_to_start)
        return fmt::format("{}: {} limit switch met at {:.3f} {} while going back to where the cycle found it "
                           "(failure policy return_to_start)",
                           X, a.rule == 1 ? "negative" : "positive", a.value, u);
      return fmt::format("{}: {} limit switch met during {} at {:.3f} {}", X, a.rule == 1 ? "negative" : "positive",
                         ph, a.value, u);
    case AlarmCode::both_limits_active:
      return fmt::format("{}: both limit switches read active at once (during {})", X, ph);
    case AlarmCode::limit_switch:
      // An axis at rest in its own phases (idle, or done since its cycle)
      // moves only with its gantry partner, or coasting: "during done" said nothing.
      if (a.phase == Phase::idle || a.phase == Phase::done)
        return fmt::format("{}: {} limit switch tripped at {:.3f} {} while the axis moved outside homing (a jog or "
                           "move, its own or its gantry partner's)",
                           X, a.rule == 1 ? "negative" : "positive", a.value, u);
      return fmt::format("{}: {} limit switch tripped during {} at {:.3f} {}", X,
                         a.rule == 1 ? "negative" : "positive", ph, a.value, u);
    case AlarmCode::encoder_reversed:
      return fmt::format("{}: the encoder counted {:.3f} {} away from the mechanical stop while the motor pushed "
                         "toward it (stall_detect following_error)", X, a.value, u);
    case AlarmCode::travel_end_not_found:
      return fmt::format("{}: measurement found no end of travel within {:.3f} {} of the home (max_seek_travel "
                         "{:g} {}): no {} met", X, a.value, u, s.max_seek_travel_mm, u,
                         s.limits_fitted ? "limit switch" : "stall at a hard stop");
    case AlarmCode::switch_not_repeatable:
      return fmt::format("{}: switch not repeatable: spread {:.3f} {} over {} passes, limit {:.3f} {}", X, a.value,
                         u, latch_passes_of(s.latch_passes), s.max_latch_spread_mm, u);
  }
  return "?";
}

}  // namespace

std::string describe_alarm(std::size_t axis, const Alarm& a, const Settings& settings) {
  if (a.code == AlarmCode::none) return "";
  if (!entry_of(a.code)) return "?";  // a number no alarm has
  return fmt::format("{}; {}", what_happened(axis, a, settings), alarm_what_to_check(a.code));
}

std::string describe_global_alarm(AlarmCode code, const Settings& settings) {
  // An e-stop pressed at rest belongs to the machine, not to axis X.
  if (code == AlarmCode::emergency_stop)
    return fmt::format("emergency stop pressed; {}", alarm_what_to_check(code));
  return describe_alarm(0, Alarm{code}, settings);
}

}  // namespace homing
