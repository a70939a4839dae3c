#pragma once
// The engine's state of one axis between periods. What only one phase needs
// lives in that phase's data and goes with the phase; what a homing cycle
// establishes for the gantry partner to wait on is one milestone.
#include <cstdint>
#include <optional>
#include <variant>

#include "alarms.hpp"
#include "health.hpp"
#include "home_frame.hpp"
#include "measure.hpp"
#include "motion.hpp"
#include "phases.hpp"
#include "trust.hpp"

namespace homing {

// What a waiting axis waits for from its gantry partner.
enum class Wait : std::uint8_t {
  none,                  // a later sequence step
  partner_stopped,
  partner_assigned,
  slave_aligned,
  master_at_reference,
  slave_locked,
  partner_released,      // at the release edge of this latch pass
  partner_latched,       // at the trigger edge of this latch pass, not the last
  partner_at_reference,
};

// Data of one phase, born when the phase is entered.
namespace phase_data {
struct Seek {
  bool at_latch = false;   // just off both sensors: the pair meets them again slowly
};
struct Stop {
  double trigger_mm = 0;        // motor position at the seek trigger
  double trigger_period_s = 0;  // length of the period in which it was seen
};
struct BackOff {
  bool index_seen = false;      // switch + index: a pulse passed during the back-off
  double index_seen_mm = 0;     // motor position of the last one
};
struct Index {
  double release_mm = 0;        // the search runs from the release edge, away from the sensor
};
struct Waiting {
  Wait wait = Wait::none;
  Phase next = Phase::idle;     // where waiting goes once the partner is ready
  double since_s = 0;           // engine time it began
};
struct Jog {
  std::int8_t dir = 0;
};
struct PushToStop {
  double start_s = 0;           // engine time the push began
  bool stalled = false;         // the stop was told (stall input or following error): braking at the stop
  // Following-error detection: motor position and encoder reading as the push began.
  double motor_start_mm = 0;
  double encoder_start_mm = 0;
};
struct LimitReversal {
  bool braked = false;        // at rest after meeting the limit switch: the search runs back
};
struct Return {
  bool under_way = false;     // every axis came to rest: moving back to where the cycle found it
};
struct DriveHoming {
  double request_s = 0;       // engine time the home request was raised
  bool done_seen_off = false; // home done was seen off since the request: the drive began homing
};
// The reference check (refcheck_phases.cpp), one phase in steps.
struct RefCheck {
  enum class Step : std::uint8_t {
    cross_cam,     // a home cam's far side: back across the cam to the frame's rest point, at seek feedrate
    leave_sensor,  // started on the switch: off it at latch feedrate to its release edge
    approach,      // toward the switch at latch feedrate to its trigger edge
    back_off,      // release methods: off the switch again, to the release edge
    go_back,       // judged: back to where the check started (or off the switch)
    release,       // accepted, a shared limit back there still held active: off it until it releases
  };
  Step step = Step::approach;
  double start_mm = 0;     // motor position where the check started
  double expected_mm = 0;  // motor position where the stored position puts the reference edge
  double trigger_mm = 0;   // motor position of the trigger edge found, in back_off
  bool started_on_sensor = false;
  bool accepted = false;   // in go_back: the edge lay within refcheck_tolerance
  bool released = false;   // a shared limit held active at the end was led off it once
  double offset_mm = 0;    // in go_back, accepted: the axis's offset that puts the edge found where expected
};
// The commissioning measurement (measure_phases.cpp), one phase in steps.
struct Measure {
  enum class Step : std::uint8_t {
    travel,      // away from home at latch feedrate until the end is told, within max_seek_travel
    brake,       // the end told: braking (a hard stop: still at reduced current)
    leave,       // a limit switch: off it again at latch feedrate until it releases
    settle,      // released (a limit switch) or pulled off the stop (a hard stop): coming to rest
  };
  Step step = Step::travel;
  double toward = 0;       // +1/-1: the direction travelled, away from home
  double start_mm = 0;     // motor position where the travel began (the bound counts from here)
  double end_mm = 0;       // motor position where the end was told
};
}  // namespace phase_data

using PhaseData = std::variant<std::monostate, phase_data::Seek, phase_data::Stop,
                               phase_data::BackOff, phase_data::Index, phase_data::Waiting, phase_data::Jog,
                               phase_data::PushToStop, phase_data::DriveHoming,
                               phase_data::LimitReversal, phase_data::Return, phase_data::RefCheck,
                               phase_data::Measure>;

// How far this axis has come in the running homing cycle, in order. The
// gantry partner waits on it.
enum class Reached : std::uint8_t {
  nothing,
  stopped_on_sensor,   // the seek trigger was found and the axis came to rest
  released,            // the back-off found the release edge
  reference,           // the reference edge is located (reference_mm)
  aligned,             // commutator slave: on its own edge, locked to its master again
  assigned,            // home position assigned
};

// The locking indexer of an axis (indexer.cpp), apart from its phase: a
// homing phase, jog or move keeps its phase while the indexer holds it.
enum class IndexerState : std::uint8_t {
  none,         // the axis has no locking indexer (axis.<a>.indexer_lock off)
  locked,       // unlock output off, confirmed locked
  unlocking,    // unlock output on, motion held until it reports unlocked
  unlocked,     // unlock output on, confirmed unlocked: the axis may move
  locking,      // at rest, unlock output off, waiting for it to report locked
  lock_failed,  // lock_not_confirmed raised: output off, locked once it reports so
};
struct Indexer {
  IndexerState state = IndexerState::none;
  double since_s = 0;  // engine time the state was entered
  bool unlock_output() const {
    return state == IndexerState::unlocking || state == IndexerState::unlocked;
  }
  // Motion passes only while confirmed unlocked (or on an axis without one).
  bool lets_move() const { return state == IndexerState::none || state == IndexerState::unlocked; }
};

// What this period's inputs say of the axis's drive and encoder.
struct AxisReadings {
  bool drive_fault = false;
  bool absolute_valid = false;
  double absolute_mm = 0;  // absolute encoder reading
  bool stall = false;      // the drive reports a stall (torque limit reached)
  bool drive_done = false;  // the drive's home done
  bool limit_min = false;   // the negative end's limit switch is active (limits fitted, polarity applied)
  bool limit_max = false;   // the positive end's
  // The limit switch at the end `toward` points to (-1 negative, +1 positive) is active.
  bool limit_toward(double toward) const { return toward < 0 ? limit_min : limit_max; }
};

struct AxisRun {
  Phase phase = Phase::idle;
  PhaseData data{};             // of the current phase
  bool entered = false;         // the current phase has run its entry action
  double phase_start_mm = 0;    // motor position at phase entry
  double target_mm = 0;         // of the current move_to

  Alarm alarm{};
  MotionState motor{};          // motor position now (never jumps: steps counted)
  MotionState period_start{};   // motor at the start of the period that just ended
  MotionCommand command{};      // what runs until the next period
  MotionCommand last_command{}; // what ran during the period that just ended
  double offset_mm = 0;         // machine position = motor + offset
  std::optional<HomeFrame> home;  // while homed: the frame it was homed in (home_frame.hpp)
  AxisReadings readings{};      // this period's
  bool push_output = false;
  bool commutator_output = false;
  std::int8_t prev_jog_request = 0;  // the jog input of the last period (a jog starts on a change)
  bool limit_tripped = false;   // shared limit or limit switch tripped: jog away until it releases
  // Which: 0 the shared home sensor (it lies toward `direction`), -1/+1 the
  // limit switch at the negative/positive end.
  std::int8_t limit_side = 0;
  // The soft limits of the last period (nullopt: off). When a change of them
  // leaves this jogging or moving axis unable to stop inside them: the
  // machine position its braking may reach, which is no overrun (the limit
  // came to the axis); nullopt once it rests (safety.cpp).
  std::optional<std::pair<double, double>> soft_limits_seen;
  std::optional<double> moved_limits_bound_mm;
  double pair_rel0_mm = 0;      // gantry slave: slave - master motor position at cycle start
  // Gantry slave: slave - master motor position where the pair is square as
  // far as the module knows: when both sides were last assigned their home,
  // or (never homed as a pair since the start) where the first cycle found it.
  // An alarm may leave the pair racked; the next cycle counts from this.
  std::optional<double> pair_square_mm;
  int pair_square_master = -1;  // the master that square was measured against
  // Homed by its drive (drive mode): from then on the drive's home done must
  // stay on, or the drive has lost the reference the coordinate rests on.
  bool drive_referenced = false;
  Indexer indexer{};

  // The homing cycle.
  bool in_cycle = false;
  Reached reached = Reached::nothing;
  double reference_mm = 0;      // motor position at the reference edge
  bool follow_master = false;   // slave: locked to the master's motion
  bool aligning = false;        // commutator slave: running its own edge search
  double trigger_position_mm = 0;  // reported: reference edge in the coordinates believed before
  double home_correction_mm = 0;   // reported: assigned - believed at the reference edge
  bool homed_at_cycle_start = false;  // reported: homed when its last cycle started
  double cycle_start_mm = 0;    // motor position as its cycle started (failure policy return_to_start)
  bool moved_in_cycle = false;  // its motor ran in this cycle
  bool started_on_limit = false;  // a limit switch was active as its cycle started
  // In this cycle it pushed into its mechanical stop or its drive homed it:
  // its counted steps no longer say how far its carriage went.
  bool steps_off_carriage = false;
  CycleEdges edges{};           // this cycle's seek trigger and first release
  LatchEdges latch{};           // this cycle's slow approaches to the reference edge
  SwitchHealth health{};        // reported: what the last cycle measured of the switch
  std::uint32_t positions_set = 0;  // reported: set-position commands carried out

  // Position trust (trust.hpp).
  std::optional<HomeFrame> restored;  // its stored last stop was clean in this frame: a reference check is offered
  bool checking = false;              // the running cycle is this axis's reference check
  bool homed_by_check = false;        // its reference came from a reference check
  double refcheck_error_mm = 0;       // reported: the last check's edge found less where it was expected

  // The commissioning measurement (measure.hpp).
  bool measuring = false;             // the running cycle homes this axis, then measures its travel
  Measurement measurement{};          // reported: the last measurement's figures (0 until one found its end)

  bool homed() const { return home.has_value(); }
  // Where the axis is is no longer known: not homed, and its stored
  // position no longer offered for a reference check.
  void lose_reference() {
    home.reset();
    restored.reset();
  }
  Trust trust() const {
    if (homed()) return homed_by_check ? Trust::reference_checked : Trust::homed_this_power_on;
    return restored ? Trust::last_stop_clean : Trust::unknown;
  }
  // Homed, or its method does not home (disabled): what jogs, moves and the
  // homed status go by.
  bool counts_as_homed(HomingMode mode) const { return homed() || !mode_homes(mode); }
  bool moving() const { return motor.velocity_mm_per_s != 0; }
  // Homing, jogging, moving, braking, or still in motion: what the status
  // register axis.<a>.busy shows.
  bool busy() const {
    return in_cycle || phase == Phase::jog || phase == Phase::move || phase == Phase::stopping || moving() ||
           indexer.state == IndexerState::unlocking || indexer.state == IndexerState::locking;
  }
  // What axis.<a>.phase shows: the indexer's unlock or lock while it holds
  // the axis or locks it after rest, else the phase.
  Phase shown_phase() const {
    if (indexer.state == IndexerState::unlocking) return Phase::unlock;
    if (indexer.state == IndexerState::locking) return Phase::lock;
    return phase;
  }
  double machine_position_mm() const { return motor.position_mm + offset_mm; }
  // The coordinate the axis is given where it stands, without a reference
  // edge (manual, absolute, an axis in no sequence step): its home position,
  // or the absolute encoder's reading less home_position (nullopt while the
  // reading is not valid).
  std::optional<double> coordinate_where_it_stands(const AxisSettings& s) const {
    if (mode_row(s.mode).coordinate != Coordinate::absolute_encoder) return s.home_position_mm;
    if (!readings.absolute_valid) return std::nullopt;
    return readings.absolute_mm - s.home_position_mm;
  }
  // A new phase starts with no data.
  void set_phase(Phase p) {
    phase = p;
    data = std::monostate{};
  }
  // The current phase's data, made on first use in the phase.
  template <class T>
  T& phase_data() {
    if (!std::holds_alternative<T>(data)) data.emplace<T>();
    return std::get<T>(data);
  }
  template <class T>
  const T* phase_data_if() const {
    return std::get_if<T>(&data);
  }
  void reach(Reached r) {
    if (r > reached) reached = r;
  }
  bool has_reached(Reached r) const { return reached >= r; }
  Wait waiting_for() const {
    const auto* w = phase_data_if<phase_data::Waiting>();
    return phase == Phase::waiting && w ? w->wait : Wait::none;
  }
  std::int8_t jog_dir() const {
    const auto* j = phase_data_if<phase_data::Jog>();
    return phase == Phase::jog && j ? j->dir : 0;
  }
};

}  // namespace homing
