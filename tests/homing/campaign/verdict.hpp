#pragma once
// What may (and what must) come out of one cycle: each alarm from a cause
// that explains it on the axis it names, each cause that must show as its
// own alarm on the axis it hits (or its gantry partner), a homed machine
// with the coordinates its modes define, within the cycle's distance bounds.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "machine.hpp"
#include "watch.hpp"

namespace campaign {

// One thing wrong with the machine or done to it: the alarm codes it may
// raise and on which axes; whether it must show as one of them; and, for a
// cause that strikes one axis at one moment (a drive fault), the phase that
// axis was in, which its alarm must carry.
struct Cause {
  std::string what;          // this instance, with its axis
  std::string kind;          // the failure class when it does not show ("" = what)
  AlarmBits codes = 0;   // bit per AlarmCode, on `axes`
  AxisMask axes = 0;
  AlarmBits global = 0;  // bit per AlarmCode, as the global alarm
  bool must = false;
  // It must show only while the axis's sensor tells the truth: a sensor fault
  // struck during the cycle may end the search anywhere (Run::apply).
  bool needs_true_sensor = false;
  std::optional<std::size_t> phase_axis;
  Phase phase = Phase::idle;       // the axis's phase when it struck
  Phase phase_seen = Phase::idle;  // ... and in the period the engine first read it
};

AlarmBits code_bits(std::initializer_list<AlarmCode> codes);

struct Causes {
  std::vector<Cause> list;
  // An abort that found no axis still homing (all done, between two steps)
  // stops the cycle with no alarm to raise: it ends uncounted.
  bool aborted_quietly = false;
  Cause& add(std::string what, std::initializer_list<AlarmCode> codes, AxisMask axes, bool must = false);
  // Every alarm a lying sensor can make the edge search raise.
  Cause& sensor_fault(std::string what, AxisMask axes, bool must = false);
  // ... and, on an axis with limit switches, those a home cam's search or latch can then meet.
  Cause& sensor_fault(std::string what, AxisMask axes, const Settings& s, bool must = false);
  bool any_must() const;
};

// What is wrong with the machine as the cycle starts.
// rack: per gantry slave, how far out of square (from where it was last
// square, as the module counts) the pair stands as the cycle starts; nullopt
// when a side lost steps or slipped since (then a misalignment may come).
Causes standing_causes(rig::Rig& r, const Machine& m, const CyclePlan& plan, bool refused, AxisMask encoder_invalid,
                       const std::array<std::optional<double>, kAxisCount>& rack);
// An event applied while the cycle ran (the status as it stood when it was applied).
void event_cause(Causes& c, const Event& e, const Settings& s, const Status& st, const CyclePlan& plan);
// A locking indexer's fault applied while the cycle ran: exactly the alarm it
// produces, from where the indexer stood (unlock_output: the engine's unlock
// output; pin_in: the simulated pin; motor_running: the motor still runs
// when the engine next looks) and whether the axis has yet to move.
void indexer_cause(Causes& c, const Event& e, const Settings& s, const Status& st, const CyclePlan& plan,
                   bool unlock_output, bool pin_in, bool motor_running);

// Every alarm the watch saw is explained by a cause on its axis and every
// cause that must show did: "" when so, else what is wrong.
struct Unexplained {
  std::string what;    // the failure's class
  std::string detail;  // figures
};
std::optional<Unexplained> explain(const Watch& w, const Causes& causes, const Settings& s);

// Longest carriage path an axis may travel in one cycle, alarm stop included.
// x_start: the carriage where the cycle started.
double path_bound(rig::Rig& r, const Machine& m, std::size_t a, double x_start);
// Longest a cycle may run (machine time).
double time_bound(rig::Rig& r, const Machine& m, const CyclePlan& plan);

// The end of a cycle, the machine at rest.
void verdict(Watch& w, rig::Rig& r, const Machine& m, const Causes& causes, std::uint32_t cycles_before);

std::string alarm_list(AlarmBits bits);
std::string axis_letters(AxisMask m);

}  // namespace campaign
