#pragma once
// The configuration check run before any motion (and by the register layer on
// every settings write): refuses settings that cannot work, naming the setting.
#include <cstdint>
#include <array>
#include <optional>
#include <string>

#include "alarms.hpp"
#include "enum_info.hpp"
#include "settings.hpp"

namespace homing {

enum class CheckRule : std::uint8_t {
  none = 0,
  not_positive,             // a feedrate, acceleration or travel that must be > 0
  latch_not_slower,         // latch feedrate must be below seek feedrate
  stop_distance_too_long,   // v²/2a + v·debounce beyond max_stop_distance
  negative,                 // a distance that must be >= 0
  missing_distance,         // pre-move, push or index pitch needed by the mode
  slave_invalid,            // slave_of names itself, a slave, or an axis that does not home
  slave_needs_sensor,       // a software-slaved axis must have its own home sensor
  commutator_needs_switch_master,  // a gantry's master may not home in a pushing mode
  soft_limits_inverted,
  outside_soft_limits,      // home or final position outside the enabled soft limits
  disabled_in_gantry,       // a disabled axis is neither master nor slave
  slave_of_slave,           // the master named is itself a slave
  gantry_stop_too_long,     // the pair cannot stop within max_misalignment
  squaring_beyond_misalignment,  // pull-off difference + compensation alone exceed max_misalignment
  backoff_too_short,        // max_backoff cannot release the sensor after the stop (and push)
  shared_limit_rests_on_sensor,  // a shared home/limit sensor needs a pull-off off the sensor
  shared_limit_without_sensor,   // the homing method has no home sensor to share with a limit
  kind_linear_only,         // X, Y and Z cannot be rotary
  missing_time_limit,       // drive mode needs drive_home_timeout_s > 0
  indexer_in_gantry,        // a locking indexer on a gantry master or slave
  cam_needs_limits,         // home_cam reverses at limit switches: limits_fitted must be on
  limit_overtravel_too_short,  // the axis cannot stop within limit_overtravel past a limit switch
  following_error_in_noise,    // max_following_error within what the encoder and a moving axis show anyway
  following_error_beyond_travel,  // max_following_error can never be reached within max_seek_travel
};

// Each rule in words, for the refusal codes a PLC reads
// (status.last_refusal_reason = 100 + rule) and hmi_maps/refusals.csv.
inline constexpr EnumInfo<CheckRule> kCheckRuleInfo[] = {
    {CheckRule::none, "none", "no rule broken"},
    {CheckRule::not_positive, "not_positive", "a feedrate, acceleration or travel must be greater than 0"},
    {CheckRule::latch_not_slower, "latch_not_slower", "the latch feedrate must be below the seek feedrate"},
    {CheckRule::stop_distance_too_long, "stop_distance_too_long",
     "the seek cannot stop within max_stop_distance (v^2/2a plus the travel while debouncing)"},
    {CheckRule::negative, "negative", "this distance must not be negative"},
    {CheckRule::missing_distance, "missing_distance",
     "the homing mode needs this distance (pre-move, push or index pitch) greater than 0"},
    {CheckRule::slave_invalid, "slave_invalid",
     "slave_of must name another axis that homes and is not itself a slave"},
    {CheckRule::slave_needs_sensor, "slave_needs_sensor", "a software-slaved axis needs its own home sensor"},
    {CheckRule::commutator_needs_switch_master, "commutator_needs_switch_master",
     "the master of an external-commutator gantry must home on a switch, not by pushing"},
    {CheckRule::soft_limits_inverted, "soft_limits_inverted", "soft_limit_max must be above soft_limit_min"},
    {CheckRule::outside_soft_limits, "outside_soft_limits",
     "the home or final position lies outside the enabled soft limits"},
    {CheckRule::disabled_in_gantry, "disabled_in_gantry", "a disabled axis can be neither master nor slave"},
    {CheckRule::slave_of_slave, "slave_of_slave", "the master named is itself a slave"},
    {CheckRule::gantry_stop_too_long, "gantry_stop_too_long",
     "the gantry pair cannot stop within max_misalignment from its fastest speed"},
    {CheckRule::squaring_beyond_misalignment, "squaring_beyond_misalignment",
     "the pull-off difference plus switch compensation alone exceed max_misalignment"},
    {CheckRule::backoff_too_short, "backoff_too_short",
     "max_backoff cannot release the sensor after the stop (and the push)"},
    {CheckRule::shared_limit_rests_on_sensor, "shared_limit_rests_on_sensor",
     "a home sensor shared with a limit needs a pull-off that leaves the sensor"},
    {CheckRule::shared_limit_without_sensor, "shared_limit_without_sensor",
     "shared_limit needs a homing method with a home sensor to share"},
    {CheckRule::kind_linear_only, "kind_linear_only",
     "X, Y and Z are linear axes: only A, B and C can be rotary"},
    {CheckRule::missing_time_limit, "missing_time_limit",
     "drive-performed homing needs drive_home_timeout_s greater than 0"},
    {CheckRule::indexer_in_gantry, "indexer_in_gantry",
     "a locking indexer (indexer_lock) is for an axis of its own, not a gantry master or slave"},
    {CheckRule::cam_needs_limits, "cam_needs_limits",
     "home_cam reverses its search at the limit switches: it needs limits_fitted"},
    {CheckRule::limit_overtravel_too_short, "limit_overtravel_too_short",
     "the axis cannot stop within limit_overtravel past a limit switch from its seek or jog feedrate"},
    {CheckRule::following_error_in_noise, "following_error_in_noise",
     "max_following_error must exceed the encoder's resolution and noise and what a moving axis lags anyway"},
    {CheckRule::following_error_beyond_travel, "following_error_beyond_travel",
     "max_following_error must be shorter than max_seek_travel, or the stop can never be told"},
};
static_assert(lists_every_value(kCheckRuleInfo, CheckRule::following_error_beyond_travel));
constexpr std::span<const EnumInfo<CheckRule>> enum_table(CheckRule) { return kCheckRuleInfo; }

// What to change for each rule, for a technician at a panel
// (hmi_maps/refusals.csv "fix"; the log's line adds the figures).
struct CheckRuleFix {
  CheckRule value;
  std::string_view fix;
};
inline constexpr CheckRuleFix kCheckRuleFix[] = {
    {CheckRule::none, ""},
    {CheckRule::not_positive, "write a value greater than 0"},
    {CheckRule::latch_not_slower, "lower latch_feedrate below seek_feedrate, or raise seek_feedrate first"},
    {CheckRule::stop_distance_too_long,
     "lower seek_feedrate or debounce_ms, raise acceleration, or raise max_stop_distance first"},
    {CheckRule::negative, "write 0 or more"},
    {CheckRule::missing_distance,
     "set the distance this mode needs (pre_move_distance, push_distance or index_pitch) above 0 first, "
     "or choose another mode"},
    {CheckRule::slave_invalid, "name another axis (1 = X ... 6 = C) whose mode homes, or 0 for no gantry"},
    {CheckRule::slave_needs_sensor,
     "give the slave a switch mode with its own sensor, or drive it through an external commutator (slave_mode 1)"},
    {CheckRule::commutator_needs_switch_master,
     "give the master a switch mode (switch_release, switch_reapproach, switch_index), or use a software-slaved pair"},
    {CheckRule::soft_limits_inverted, "write soft_limit_max above soft_limit_min (raise the maximum first)"},
    {CheckRule::outside_soft_limits,
     "move home_position or final_position inside the soft limits, widen the limits first, or switch them off"},
    {CheckRule::disabled_in_gantry, "set slave_of = 0 first, or give both axes a homing mode"},
    {CheckRule::slave_of_slave, "name the pair's master (an axis that is no slave)"},
    {CheckRule::gantry_stop_too_long,
     "lower the master's seek and jog feedrates, raise the accelerations of both sides, or raise the slave's "
     "max_misalignment first"},
    {CheckRule::squaring_beyond_misalignment,
     "bring the two pull-offs closer, lower switch_compensation, or raise the slave's max_misalignment first"},
    {CheckRule::backoff_too_short,
     "raise max_backoff first, or lower seek_feedrate or push_distance, or raise acceleration"},
    {CheckRule::shared_limit_rests_on_sensor, "raise pull_off so that the axis comes to rest off the sensor"},
    {CheckRule::shared_limit_without_sensor, "set shared_limit = 0, or choose a mode with a home sensor"},
    {CheckRule::kind_linear_only, "leave X, Y and Z linear (kind 0); put a rotary axis on A, B or C"},
    {CheckRule::missing_time_limit, "set drive_home_timeout_s above 0 (longer than the drive's own homing takes)"},
    {CheckRule::indexer_in_gantry, "switch indexer_lock off, or take the axis out of the gantry (slave_of = 0)"},
    {CheckRule::cam_needs_limits, "set limits_fitted = 1 and wire both limit switches, or choose another mode"},
    {CheckRule::limit_overtravel_too_short,
     "lower seek_feedrate or jog_feedrate, raise acceleration, or raise limit_overtravel to what the machine has"},
    {CheckRule::following_error_in_noise,
     "raise max_following_error above the encoder's noise and the lag at latch_feedrate, or lower latch_feedrate"},
    {CheckRule::following_error_beyond_travel, "lower max_following_error, or raise max_seek_travel first"},
};
static_assert(lists_every_value(kCheckRuleFix, CheckRule::following_error_beyond_travel));
constexpr std::string_view rule_fix(CheckRule rule) {
  const auto i = static_cast<std::size_t>(rule);
  return i < std::size(kCheckRuleFix) ? kCheckRuleFix[i].fix : std::string_view{};
}

struct SettingsFault {
  std::size_t axis = 0;
  AxisField field = AxisField::none;
  CheckRule rule = CheckRule::none;
  double value = 0;  // the figure that breaks the rule (e.g. the needed stop distance)
  AlarmCode code() const {
    return rule == CheckRule::slave_needs_sensor ? AlarmCode::slave_sensor_missing
                                                 : AlarmCode::settings_fault;
  }
};

// The one rule set. Checks one axis as it would move (jog, move, homing, in a
// sequence step or not), with the settings it moves with (gantry.hpp). The
// whole settings are needed for gantries. The engine runs it before every
// cycle, jog and move; the register validation and the tools run it on every
// write, so what the engine would refuse is refused at write time first.
std::optional<SettingsFault> check_axis(const Settings& settings, std::size_t axis);

// The first broken rule of each axis.
using SettingsFaults = std::array<std::optional<SettingsFault>, kAxisCount>;
SettingsFaults check_settings(const Settings& settings);

// A fault of `after` that `before` does not have (same axis, setting and
// rule): what a write would break. Settings already broken before the write
// (an old database) do not block writes that leave them as they are.
std::optional<SettingsFault> new_fault(const Settings& before, const Settings& after);

// Stop distance of the seek, including the travel while the input is debounced.
double seek_stop_distance_mm(const AxisSettings& s);
// Distance the back-off may have to travel before the sensor can release:
// the seek's stop distance plus, in pushing modes, the push.
double backoff_needed_mm(const AxisSettings& s);
// A gantry pair's stop distance from its fastest speed (seek or jog) at the
// pair's acceleration: one side stalled by a drive fault, the other must
// come to rest within max_misalignment.
double gantry_stop_distance_mm(const AxisSettings& pair_motion);
// Travel past a limit switch before the axis can rest: the stop from its
// fastest speed (seek or jog feedrate) plus a 20 ms control period of travel
// before the switch is seen.
double limit_stop_distance_mm(const AxisSettings& s);
// Hard-stop homing by following error: what one reading of the encoders this
// module is made for may be off by (their resolution and noise together).
inline constexpr double kEncoderReadingError_mm = 0.002;
// The least max_following_error that tells a stop: ten readings' error (the
// following error is the difference of two readings, and encoder_reversed
// looks for a quarter of the limit) plus the latch feedrate's travel in the
// longest control period (kBrakingHorizon_s: the steps and the encoder may be
// read that far apart, so a moving axis shows that much anyway).
double following_error_floor_mm(const AxisSettings& s);
// The final move of a cycle is made for this axis.
bool final_move_wanted(const AxisSettings& s);
// How far the index phase searches from the release edge before
// index_not_found: a pitch and a tenth, plus the stop from latch feedrate.
double index_search_mm(const AxisSettings& s);

std::string describe_fault(const SettingsFault& fault, const Settings& settings);

}  // namespace homing
