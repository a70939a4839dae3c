#pragma once
// One run of the campaign: a generated machine, powered up, homed, and put
// through random acts (faults, aborts, resets, re-homes, jogs, moves, lost
// steps, a hard-limit trip), every period checked by the Watch.
#include <cstdint>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "coverage.hpp"
#include "dice.hpp"
#include "machine.hpp"
#include "verdict.hpp"
#include "watch.hpp"

namespace campaign {

// The campaign's TEST_CASE: a seed replays with
//   HOMING_CAMPAIGN_SEED=<seed> HOMING_CAMPAIGN_RUNS=1 build/bin/homing_tests "<kTestName>"
inline constexpr const char* kTestName = "the campaign: random machines over the whole configuration space";

// What a run got to do (for the survey's coverage figures).
namespace act {
inline constexpr std::uint32_t homed = 1u << 0;
inline constexpr std::uint32_t homed_software_gantry = 1u << 1;
inline constexpr std::uint32_t homed_commutator_gantry = 1u << 2;
inline constexpr std::uint32_t event_in_cycle = 1u << 3;
inline constexpr std::uint32_t jog_and_move = 1u << 4;
inline constexpr std::uint32_t hard_limit_recovered = 1u << 5;
inline constexpr std::uint32_t lost_steps_corrected = 1u << 6;
inline constexpr std::uint32_t start_button_cycle = 1u << 7;
inline constexpr std::uint32_t rehomed = 1u << 8;
inline constexpr std::uint32_t alarm_then_homed = 1u << 9;
inline constexpr std::uint32_t motion_before_homing = 1u << 10;
inline constexpr std::uint32_t event_in_jog_or_move = 1u << 11;
inline constexpr std::uint32_t settings_changed = 1u << 12;
inline constexpr std::uint32_t limit_switch_recovered = 1u << 13;
inline constexpr std::uint32_t measured = 1u << 14;
inline constexpr std::uint32_t refchecked = 1u << 15;
inline constexpr int kCount = 16;
inline const char* name(int i) {
  static const char* names[] = {"homed",           "homed a software-slaved gantry", "homed a commutator gantry",
                                "event in a cycle", "jogged and moved",             "recovered from a hard-limit trip",
                                "lost steps corrected", "cycle started by the button", "homed again",
                                "homed after an alarm", "jogged or moved before homing",
                                "event in a jog or move", "settings written between cycles",
                                "recovered from a limit switch trip", "measured an axis's travel",
                                "homed by a reference check after a restart"};
  return names[i];
}
}  // namespace act

struct Outcome {
  std::uint64_t seed = 0;
  bool failed = false;
  Failure failure{};
  std::string story;  // the machine
  std::string log;    // what the script did, when
  bool ever_homed = false;
  bool refused = false;
  std::string unexpected_refusal;  // the check refused a machine generated to be valid
  std::uint64_t periods = 0;
  std::uint32_t acts = 0;
  RunCoverage coverage;
};

class Run {
 public:
  explicit Run(std::uint64_t seed);
  Outcome run();

 private:
  bool ok() const { return !w_->failed(); }
  void step() { r_.step(); }
  // An event during a jog or a move, and the period after it: an input the
  // simulator changed is read by the engine in the next period, whose phase
  // its alarm may carry (a move may arrive meanwhile: campaign seed 31342370).
  void apply_in_motion(const Event& e, Causes& causes);
  void settle(double max_s = 10);
  void say(const std::string& what);
  void power_up();
  // measure: the axis a measurement (cmd.measure) homes and measures instead of homing `mask`.
  bool cycle(bool all, AxisMask mask, std::vector<Event> events, bool by_button, AxisMask measure = 0);
  void apply(const Event& e, Causes& causes, const CyclePlan& plan);
  void motion_before_homing();
  std::optional<Event> motion_event(std::size_t a);
  void recover();
  void jog_invalid_slave();
  void put_back(AxisMask mask);
  void exercise_motion();
  void hard_limit_recovery();
  // limit_acts.cpp: a homed axis jogged or moved into a limit switch, and off it again.
  void limit_switch_trip();
  void final_move_into_limit(Causes& causes, AxisMask& seen_final);
  void jog_off_limit_switch(std::size_t a, int away);
  bool on_limit_switch(std::size_t a);  // limits fitted, not faulted, one of them active
  void lost_steps();
  // service_acts.cpp: the commissioning measurement, and a daemon restart with reference checks.
  void measurement();
  CommandResult measure_expected(AxisMask mask);
  double measure_lag_mm(std::size_t a);
  void measure_refused(AxisMask mask, bool home_all_only);
  void measure_axis(std::size_t a);
  void measure_period(Causes& causes);  // each period of a measurement's cycle
  void restart_with_checks();
  CommandResult refcheck_expected(AxisMask mask, const std::array<bool, kAxisCount>& offered);
  double refcheck_slack_mm(std::size_t a);
  void refcheck_refused(AxisMask mask, const std::array<bool, kAxisCount>& offered);
  void refcheck(AxisMask mask, const std::array<Truth, kAxisCount>& truth, const std::array<bool, kAxisCount>& homed,
                const std::array<double, kAxisCount>& moved);
  void change_settings();
  void limit_sensor_faults(Causes& causes);  // indexer_faults too
  void indexer_faults(Causes& causes);
  std::size_t pick(const std::vector<std::size_t>& cand);  // one of them, at random
  AxisMask with_slave(std::size_t a) const;
  std::vector<Event> random_events(const CyclePlan& plan, double estimate);
  std::vector<Event> common_events(const CyclePlan& plan, double estimate);
  void add_indexer_event(std::vector<Event>& events, const CyclePlan& plan, double estimate);
  std::vector<Phase> phases_run(std::size_t a) const;
  void follow_ups();
  bool homed_axis(std::size_t a) const;
  // A move commanded and not yet over: moving, or still unlocking its indexer first.
  bool move_pending(std::size_t a) const;
  void mark(const std::string& key, std::uint8_t bits) { coverage_[key] |= bits; }
  void mark_machine();
  void mark_cycle(const CyclePlan& plan, const Causes& causes, bool clean);
  static const char* start_key(CamStart c);
  std::vector<std::string> home_cam_keys(std::size_t a) const;

  Machine m_;
  rig::Rig r_;
  Dice d_;
  Dice periods_;
  Dice indexer_events_;  // locking-indexer faults in later cycles (their own dice: others draw as before)
  Dice limit_acts_;      // acts at limit switches (their own dice)
  Dice measure_acts_;    // measurements (their own dice)
  Dice restarts_;        // daemon restarts and reference checks (their own dice)
  // A measurement's cycle under way: its axis, its far end (carriage
  // coordinates), and until its travel begins the carriage and the truth.
  struct MeasureRun {
    std::size_t axis = 0;
    double end = 0;
    bool began = false;
    double x_last = 0;
    bool offset_valid = false;
    double offset = 0, tol = 0;
  };
  std::optional<MeasureRun> measuring_;
  std::unique_ptr<Watch> w_;
  std::ostringstream log_;
  bool comm_lost_ = false;
  AxisMask encoder_invalid_ = 0;
  bool ever_homed_ = false;
  double last_cycle_s_ = 1;
  std::uint32_t acts_ = 0;
  int homed_cycles_ = 0;
  bool alarm_seen_ = false;
  RunCoverage coverage_;
  AxisMask cam_on_start_ = 0;  // axes whose carriage stood on its cam as the cycle began
};

Outcome run_seed(std::uint64_t seed);
// A failed run told for a reader: the failure, how to replay it, the machine, the script.
std::string report(const Outcome& o, const char* test_name = kTestName);

}  // namespace campaign
