#pragma once
// Homing settings in engineering units. The register codec (registers/) is the
// only place that converts raw Modbus integers into these values; defaults also
// live in the register table, so these structs start neutral.
#include <array>
#include <cstdint>
#include <iterator>
#include <span>
#include <string_view>

#include "axes.hpp"
#include "enum_info.hpp"
#include "modes.hpp"

namespace homing {

enum class Direction : std::uint8_t { negative = 0, positive = 1 };
inline constexpr EnumInfo<Direction> kDirectionInfo[] = {
    {Direction::negative, "negative", "seek toward the negative end"},
    {Direction::positive, "positive", "seek toward the positive end"},
};
static_assert(lists_every_value(kDirectionInfo, Direction::positive));
constexpr std::span<const EnumInfo<Direction>> enum_table(Direction) { return kDirectionInfo; }

enum class PreMove : std::uint8_t { none = 0, if_sensor_active = 1, always = 2 };
inline constexpr EnumInfo<PreMove> kPreMoveInfo[] = {
    {PreMove::none, "none", "no pre-move"},
    {PreMove::if_sensor_active, "if_sensor_active",
     "move pre_move_distance away first if the sensor is already active"},
    {PreMove::always, "always", "always move pre_move_distance away before seeking"},
};
static_assert(lists_every_value(kPreMoveInfo, PreMove::always));
constexpr std::span<const EnumInfo<PreMove>> enum_table(PreMove) { return kPreMoveInfo; }

enum class SlaveMode : std::uint8_t { own_output = 0, external_commutator = 1 };
inline constexpr EnumInfo<SlaveMode> kSlaveModeInfo[] = {
    {SlaveMode::own_output, "own_output", "own step output, own home sensor (software squaring)"},
    {SlaveMode::external_commutator, "external_commutator", "external commutator on the master's output"},
};
static_assert(lists_every_value(kSlaveModeInfo, SlaveMode::external_commutator));
constexpr std::span<const EnumInfo<SlaveMode>> enum_table(SlaveMode) { return kSlaveModeInfo; }

enum class AllowedWithoutHoming : std::uint8_t { all = 0, jog_reduced = 1, none = 2 };
inline constexpr EnumInfo<AllowedWithoutHoming> kAllowedWithoutHomingInfo[] = {
    {AllowedWithoutHoming::all, "all", "every command is allowed before homing"},
    {AllowedWithoutHoming::jog_reduced, "jog_reduced", "only jog, at reduced speed (100 mm/min)"},
    {AllowedWithoutHoming::none, "none", "nothing moves before homing"},
};
static_assert(lists_every_value(kAllowedWithoutHomingInfo, AllowedWithoutHoming::none));
constexpr std::span<const EnumInfo<AllowedWithoutHoming>> enum_table(AllowedWithoutHoming) {
  return kAllowedWithoutHomingInfo;
}

// What the rest of a homing cycle does when one axis fails (an alarm) or the
// cycle is aborted (docs/homing-methods.md "Failure policy"). An e-stop, a
// lost host link, a withdrawn permit and lost settings always stop everything.
enum class FailurePolicy : std::uint8_t { stop_all = 0, finish_independent = 1, return_to_start = 2 };
inline constexpr EnumInfo<FailurePolicy> kFailurePolicyInfo[] = {
    {FailurePolicy::stop_all, "stop_all", "every axis stops at once"},
    {FailurePolicy::finish_independent, "finish_independent",
     "the failed axis and its gantry partner stop; the other axes of the running step finish their homing; "
     "no later step starts"},
    {FailurePolicy::return_to_start, "return_to_start",
     "every axis stops, then each axis that moved in the cycle and may move safely goes back to where the cycle "
     "found it, the last step first"},
};
static_assert(lists_every_value(kFailurePolicyInfo, FailurePolicy::return_to_start));
constexpr std::span<const EnumInfo<FailurePolicy>> enum_table(FailurePolicy) { return kFailurePolicyInfo; }

// Per axis, beside global.allowed_without_homing (Repetier's MOVE_<axis>_WHEN_HOMED):
// an axis that must never move unhomed (a Z over the work) or may always move
// (a rotary table nobody crashes) says so itself.
enum class AxisAllowedWithoutHoming : std::uint8_t { as_global = 0, all = 1, jog_reduced = 2, none = 3 };
inline constexpr EnumInfo<AxisAllowedWithoutHoming> kAxisAllowedWithoutHomingInfo[] = {
    {AxisAllowedWithoutHoming::as_global, "as_global", "as global.allowed_without_homing says"},
    {AxisAllowedWithoutHoming::all, "all", "this axis: every command is allowed before homing"},
    {AxisAllowedWithoutHoming::jog_reduced, "jog_reduced", "this axis: only jog, at reduced speed (100 mm/min)"},
    {AxisAllowedWithoutHoming::none, "none", "this axis: nothing moves before homing"},
};
static_assert(lists_every_value(kAxisAllowedWithoutHomingInfo, AxisAllowedWithoutHoming::none));
constexpr std::span<const EnumInfo<AxisAllowedWithoutHoming>> enum_table(AxisAllowedWithoutHoming) {
  return kAxisAllowedWithoutHomingInfo;
}
// Which edge of a home cam in mid-travel is the reference (home_cam mode),
// named from the homing direction: the axis always leaves the cam across
// that edge at latch feedrate, whichever way it found the cam.
enum class CamEdge : std::uint8_t { behind = 0, ahead = 1 };
inline constexpr EnumInfo<CamEdge> kCamEdgeInfo[] = {
    {CamEdge::behind, "behind", "the cam's edge facing away from direction (the one a seek from the start side meets)"},
    {CamEdge::ahead, "ahead", "the cam's edge toward direction (the far side of the cam)"},
};
static_assert(lists_every_value(kCamEdgeInfo, CamEdge::ahead));
constexpr std::span<const EnumInfo<CamEdge>> enum_table(CamEdge) { return kCamEdgeInfo; }

// What an axis is: it names the unit of every length, feedrate and
// acceleration of the axis (mm or degrees). X, Y and Z are linear only; A, B
// and C are rotary unless set linear (the second motor of a linear axis, a
// gantry slave on A). A slave moves with its master's kind (gantry.hpp).
enum class AxisKind : std::uint8_t { linear = 0, rotary = 1 };
inline constexpr EnumInfo<AxisKind> kAxisKindInfo[] = {
    {AxisKind::linear, "linear", "linear axis: lengths in mm, feedrates in mm/min"},
    {AxisKind::rotary, "rotary", "rotary axis: angles in degrees, feedrates in deg/min (A, B, C only)"},
};
static_assert(lists_every_value(kAxisKindInfo, AxisKind::rotary));
constexpr std::span<const EnumInfo<AxisKind>> enum_table(AxisKind) { return kAxisKindInfo; }

// A new module's kind of each axis (the default of axis.<a>.kind): A, B, C
// rotary, X, Y, Z linear. Only the axes rotary by default may be rotary.
constexpr AxisKind default_kind(std::size_t axis) { return is_rotary(axis) ? AxisKind::rotary : AxisKind::linear; }
constexpr bool may_be_rotary(std::size_t axis) { return is_rotary(axis); }
// The unit of a length on an axis of this kind; feedrates are it per minute,
// accelerations it per s².
constexpr std::string_view unit_of(AxisKind kind) { return kind == AxisKind::rotary ? "deg" : "mm"; }

struct AxisSettings {
  HomingMode mode = HomingMode::disabled;
  Direction direction = Direction::negative;
  double seek_feedrate_mm_per_min = 0;
  double latch_feedrate_mm_per_min = 0;
  double acceleration_mm_per_s2 = 0;
  double max_seek_travel_mm = 0;
  double max_stop_distance_mm = 0;
  double max_backoff_mm = 0;
  double pull_off_mm = 0;
  double home_position_mm = 0;
  double final_position_mm = 0;
  bool final_move_enable = false;
  bool sensor_nc = false;
  double debounce_ms = 0;
  PreMove pre_move_mode = PreMove::none;
  double pre_move_distance_mm = 0;
  double push_distance_mm = 0;
  double index_pitch_mm = 0;  // travel per encoder index pulse; bounds the index phase
  std::uint8_t slave_of = 0;  // 0 none, 1..6 = master X..C (register value)
  SlaveMode slave_mode = SlaveMode::own_output;
  double max_misalignment_mm = 0;
  double switch_compensation_mm = 0;
  double soft_limit_min_mm = 0;
  double soft_limit_max_mm = 0;
  bool soft_limits_enable = false;
  bool shared_limit = false;
  double jog_feedrate_mm_per_min = 0;
  double stall_timeout_ms = 0;  // hard-stop homing: longest push toward the stop before stall_timeout
  AxisKind kind = AxisKind::linear;  // Settings gives each axis its default_kind
  double drive_home_timeout_s = 0;  // drive mode: the drive must report home done within this
  // Locking indexer (docs/homing-methods.md "Locking indexer"): unlock before any motion of
  // this axis, lock again once it rests, each confirmed within lock_timeout_ms.
  bool indexer_lock = false;
  double lock_timeout_ms = 0;
  AxisAllowedWithoutHoming allowed_without_homing = AxisAllowedWithoutHoming::as_global;
  // End-of-travel limit switches, one at each end (docs/limit-switches.md):
  // hard limits outside homing, and where a home_cam search reverses.
  bool limits_fitted = false;
  bool limits_nc = false;
  CamEdge cam_edge = CamEdge::behind;   // home_cam: the reference edge of the cam
  double limit_overtravel_mm = 0;       // travel past a limit switch before the mechanical stop
  // Several latch passes (docs/health.md): in a method that re-approaches its
  // switch, this many slow approaches; the reference is their median. 0 or 1
  // is one approach, as before.
  std::uint8_t latch_passes = 1;
  double max_latch_spread_mm = 0;  // their spread above this: switch_not_repeatable
  // Not used by the engine: a gantry slave's skew that differs from the
  // trend cycles' by more than this raises the runtime's health warning
  // gantry_skew_changed (docs/health.md); 0 = not checked.
  double max_skew_change_mm = 0;
  // Hard-stop homing: how the stop is told (the stall input, or the encoder
  // falling behind the steps by more than max_following_error_mm).
  StallDetect stall_detect = StallDetect::stall_input;
  double max_following_error_mm = 0;
  // Reference check (homing/trust.hpp): the switch edge must be found within
  // this of where the axis's stored position puts it.
  double refcheck_tolerance_mm = 0;
  friend bool operator==(const AxisSettings&, const AxisSettings&) = default;
};

struct GlobalSettings {
  std::array<AxisMask, 6> sequence_steps{};
  // A new module lets nothing but a slow jog move before it knows where it is.
  AllowedWithoutHoming allowed_without_homing = AllowedWithoutHoming::jog_reduced;
  bool alarm_clears_homed = true;
  std::uint32_t watchdog_ms = 0;
  bool permit_required = false;
  // When an axis fails or the cycle is aborted: what the other axes do.
  FailurePolicy failure_policy = FailurePolicy::stop_all;
  // Off: only home-all homes (RosettaCNC "homing of all axes only"), so a
  // machine whose axes must home in order is never homed piecemeal.
  bool single_axis_homing = true;
  // Not used by the engine: the runtime bounds the audit log and the homing
  // history with it (oldest rows pruned).
  std::uint32_t history_max_rows = 10000;
  // Not used by the engine: the runtime's trend check of the health figures
  // kept in the homing history (docs/health.md). Over an axis's last
  // trend_cycles cycles (0 = off), a figure that grew by more than
  // trend_growth_pct percent, and by at least trend_min_change_mm, warns.
  std::uint16_t trend_cycles = 0;
  std::uint16_t trend_growth_pct = 0;
  double trend_min_change_mm = 0;
  // Not used by the engine: an HMI's edit session (server/edit_sessions.hpp)
  // left this long without a write or a commit is discarded.
  std::uint16_t edit_timeout_s = 0;
  friend bool operator==(const GlobalSettings&, const GlobalSettings&) = default;
};

// Neutral axes, each of its default kind, so settings built by hand name the
// units a new module names.
constexpr std::array<AxisSettings, kAxisCount> default_kind_axes() {
  std::array<AxisSettings, kAxisCount> axes{};
  for (std::size_t a = 0; a < kAxisCount; ++a) axes[a].kind = default_kind(a);
  return axes;
}

struct Settings {
  std::array<AxisSettings, kAxisCount> axes = default_kind_axes();
  GlobalSettings global{};
  friend bool operator==(const Settings&, const Settings&) = default;
};

// Identifies one per-axis setting, so a settings fault can name it. The names
// are the suffixes of the register names (axis.<a>.<name>).
enum class AxisField : std::uint8_t {
  none = 0,
  mode,
  direction,
  seek_feedrate,
  latch_feedrate,
  acceleration,
  max_seek_travel,
  max_stop_distance,
  max_backoff,
  pull_off,
  home_position,
  final_position,
  final_move_enable,
  sensor_nc,
  debounce_ms,
  pre_move_mode,
  pre_move_distance,
  push_distance,
  index_pitch,
  slave_of,
  slave_mode,
  max_misalignment,
  switch_compensation,
  soft_limit_min,
  soft_limit_max,
  soft_limits_enable,
  shared_limit,
  jog_feedrate,
  stall_timeout_ms,
  kind,
  drive_home_timeout,
  indexer_lock,
  lock_timeout_ms,
  allowed_without_homing,
  limits_fitted,
  limits_nc,
  cam_edge,
  limit_overtravel,
  latch_passes,
  max_latch_spread,
  max_skew_change,
  stall_detect,
  max_following_error,
  refcheck_tolerance,
};
// The name of each: the suffix of its register name (axis.<a>.<name>).
struct AxisFieldInfo {
  AxisField value;
  std::string_view name;
};
inline constexpr AxisFieldInfo kAxisFieldInfo[] = {
    {AxisField::none, ""},
    {AxisField::mode, "mode"},
    {AxisField::direction, "direction"},
    {AxisField::seek_feedrate, "seek_feedrate"},
    {AxisField::latch_feedrate, "latch_feedrate"},
    {AxisField::acceleration, "acceleration"},
    {AxisField::max_seek_travel, "max_seek_travel"},
    {AxisField::max_stop_distance, "max_stop_distance"},
    {AxisField::max_backoff, "max_backoff"},
    {AxisField::pull_off, "pull_off"},
    {AxisField::home_position, "home_position"},
    {AxisField::final_position, "final_position"},
    {AxisField::final_move_enable, "final_move_enable"},
    {AxisField::sensor_nc, "sensor_nc"},
    {AxisField::debounce_ms, "debounce_ms"},
    {AxisField::pre_move_mode, "pre_move_mode"},
    {AxisField::pre_move_distance, "pre_move_distance"},
    {AxisField::push_distance, "push_distance"},
    {AxisField::index_pitch, "index_pitch"},
    {AxisField::slave_of, "slave_of"},
    {AxisField::slave_mode, "slave_mode"},
    {AxisField::max_misalignment, "max_misalignment"},
    {AxisField::switch_compensation, "switch_compensation"},
    {AxisField::soft_limit_min, "soft_limit_min"},
    {AxisField::soft_limit_max, "soft_limit_max"},
    {AxisField::soft_limits_enable, "soft_limits_enable"},
    {AxisField::shared_limit, "shared_limit"},
    {AxisField::jog_feedrate, "jog_feedrate"},
    {AxisField::stall_timeout_ms, "stall_timeout_ms"},
    {AxisField::kind, "kind"},
    {AxisField::drive_home_timeout, "drive_home_timeout_s"},
    {AxisField::indexer_lock, "indexer_lock"},
    {AxisField::lock_timeout_ms, "lock_timeout_ms"},
    {AxisField::allowed_without_homing, "allowed_without_homing"},
    {AxisField::limits_fitted, "limits_fitted"},
    {AxisField::limits_nc, "limits_nc"},
    {AxisField::cam_edge, "cam_edge"},
    {AxisField::limit_overtravel, "limit_overtravel"},
    {AxisField::latch_passes, "latch_passes"},
    {AxisField::max_latch_spread, "max_latch_spread"},
    {AxisField::max_skew_change, "max_skew_change"},
    {AxisField::stall_detect, "stall_detect"},
    {AxisField::max_following_error, "max_following_error"},
    {AxisField::refcheck_tolerance, "refcheck_tolerance"},
};
static_assert(lists_every_value(kAxisFieldInfo, AxisField::refcheck_tolerance));
constexpr std::span<const AxisFieldInfo> enum_table(AxisField) { return kAxisFieldInfo; }

std::string_view field_name(AxisField field);

// What axis s's method needs wired: its row's signals, with the stop
// detection its stall_detect chooses (modes.hpp).
constexpr Signals signals_needed(const AxisSettings& s) { return mode_row(s.mode).needs_with(s.stall_detect); }
constexpr bool needs_signal(const AxisSettings& s, Signal signal) {
  return (signals_needed(s) & static_cast<Signals>(signal)) != 0;
}
// The axis finds its mechanical stop by the encoder's following error.
constexpr bool detects_stop_by_following_error(const AxisSettings& s) {
  return mode_row(s.mode).detects_stop() && s.stall_detect == StallDetect::following_error;
}

// -1 when the axis is not a slave, else the master's index.
constexpr int master_of(const AxisSettings& s) {
  return s.slave_of == 0 ? -1 : static_cast<int>(s.slave_of) - 1;
}

// What axis a may do before it is homed: its own setting, else the global one.
constexpr AllowedWithoutHoming allowed_without_homing(const Settings& settings, std::size_t a) {
  switch (settings.axes[a].allowed_without_homing) {
    case AxisAllowedWithoutHoming::all: return AllowedWithoutHoming::all;
    case AxisAllowedWithoutHoming::jog_reduced: return AllowedWithoutHoming::jog_reduced;
    case AxisAllowedWithoutHoming::none: return AllowedWithoutHoming::none;
    case AxisAllowedWithoutHoming::as_global: break;
  }
  return settings.global.allowed_without_homing;
}

}  // namespace homing
