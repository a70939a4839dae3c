#pragma once
// One random machine of the campaign, built from a seed: settings, the
// simulated machine, the faults planned for its first cycle, and what the
// generator meant (so that a failure can be told as a story).
#include <cstdint>
#include <string>
#include <vector>

#include "homing/sim/config.hpp"
#include "rules.hpp"

namespace campaign {

enum class Role : std::uint8_t { plain, master, slave };

// Where a home_cam axis starts, seen from its seek direction: the cam ahead
// (found without reversal), behind it (the search meets the limit switch
// ahead, reverses and finds the cam), or the carriage already on the cam.
enum class CamStart : std::uint8_t { none, ahead, behind, on_cam };
const char* cam_start_name(CamStart c);

// Settings made wrong on purpose: the configuration check must refuse them.
enum class Invalid : std::uint8_t {
  none,
  zero_acceleration,
  latch_not_slower,
  stop_distance_short,
  push_beyond_backoff,
  no_index_pitch,
  soft_limits_inverted,
  home_outside_soft_limits,
  unsequenced_home_outside_soft_limits,
  slave_of_disabled,
  slave_of_slave,
  two_slaves,
  master_not_on_switch,
  slave_of_itself,
  slave_disabled,
  gantry_stop_beyond_misalignment,
  pushing_master,
  slave_without_sensor,
  shared_limit_on_sensor,
  drive_without_time_limit,
  count
};
const char* invalid_name(Invalid v);

// Things that happen to the machine at a moment of a cycle.
enum class EventKind : std::uint8_t {
  abort,
  estop,
  drive_fault,
  stuck_active,
  stuck_inactive,
  wire_break,
  comm_lost,
  permit_off,
  reset,       // a reset command while the cycle runs
  home_again,  // a second home command while the cycle runs
  drive_done_lost,  // drive mode: the drive's home done goes off for good
  // Locking indexer faults: drawn apart from the kinds above (on indexer
  // axes only, from their own dice), so machines without one draw as before.
  indexer_stuck_locked,
  indexer_never_locks,
  count
};
const char* event_name(EventKind k);
// The kinds drawn for any machine: those before the indexer faults.
inline constexpr int kCommonEventKinds = static_cast<int>(EventKind::indexer_stuck_locked);

struct Event {
  EventKind kind = EventKind::abort;
  std::size_t axis = 0;
  double at_s = 0;  // machine time into the cycle
  // Or aimed at a phase: applied `after_periods` periods after `axis` enters
  // `phase` (not at all if it never does).
  bool aimed = false;
  Phase phase = Phase::idle;
  int after_periods = 0;
};

struct AxisPlan {
  Role role = Role::plain;
  int partner = -1;
  bool commutator = false;     // pair wired through an external commutator
  bool differs = false;        // slave: the fields it inherits are random (to be ignored)
  double start_gap_mm = 0;     // from the cam edge, away from the sensor (< 0: starts on it)
  double cam_edge_mm = 0;      // real coordinates of the cam end the seek meets
  double skew_mm = 0;          // slave: generated squaring error relative to the start
  bool bad_skew = false;       // slave: skew beyond max misalignment, must end in misalignment
  double rest_rel_mm = 0;      // slave: where it rests relative to its master once square (predicted)
  double extras_mm = 0;        // slave: what that prediction may be off by (hysteresis, noise)
  double budget_mm = 0;        // slave: the largest skew of a run meant to home
  bool short_cam = false;      // cam shorter than the seek's stop
  bool rest_on_sensor = false; // shared limit that rests on its own sensor after pull-off
  sim::Fault start_fault = sim::Fault::none;  // present from power-up
  bool encoder_invalid = false;
  bool late_drive = false;     // drive mode: the drive answers after its time limit
  bool indexer = false;        // a locking indexer (axis.<a>.indexer_lock, fitted on the simulator)
  bool limits = false;         // end-of-travel limit switches fitted (axis.<a>.limits_fitted, on the simulator)
  bool following_error = false;  // hard-stop axis telling its stop by its encoder (stall_detect following_error)
  CamStart cam_start = CamStart::none;  // home_cam: where its first cycle starts
  bool cam_missing = false;    // home_cam: its cam lies beyond the limit switches
  bool cam_at_limit = false;   // home_cam: the limit switch on its reference side lies within its latch or pull-off
  bool far_stop_near = false;  // hard_stop by stall input: its far stop within a measurement's reach
  int reach_side = 0;          // +1/-1: the limit switch at that end lies within its jogs, moves or final move
};

struct Machine {
  std::uint64_t seed = 0;
  Settings settings{};
  sim::MachineConfig sim{};
  std::array<AxisPlan, kAxisCount> plan{};
  Invalid invalid = Invalid::none;
  std::size_t invalid_axis = 0;
  double max_dt_s = 0.001;          // the latest a control period may come
  bool start_held_at_powerup = false;
  int powerup_periods = 1;
  bool start_by_button = false;     // first cycle started by the physical input
  std::vector<Event> events;        // timed, during the first cycle
  double cycle_estimate_s = 1;      // rough length of the first cycle
};

Machine generate(std::uint64_t seed);
std::string story(const Machine& m);

}  // namespace campaign
