#pragma once
// What may (and what must) come out of one cycle: alarms only from their
// causes, a homed machine with the coordinates its modes define, within the
// cycle's distance bounds.
#include <cstdint>
#include <string>
#include <vector>

#include "machine.hpp"
#include "watch.hpp"

namespace campaign {

struct Causes {
  std::uint32_t allowed = 0;        // bit per AlarmCode
  std::vector<std::string> must;    // causes that must end the cycle in an alarm
  void allow(std::initializer_list<AlarmCode> codes) {
    for (AlarmCode c : codes) allowed |= 1u << static_cast<unsigned>(c);
  }
  void sensor_fault();  // a sensor that lies: every alarm of the edge search
};

// What is wrong with the machine as the cycle starts.
Causes standing_causes(rig::Rig& r, const Machine& m, const CyclePlan& plan, bool refused, AxisMask encoder_invalid);
// An event applied while the cycle ran.
void event_cause(Causes& c, const Event& e, const Settings& s);

// Longest carriage path an axis may travel in one cycle, alarm stop included.
// x_start: the carriage where the cycle started.
double path_bound(rig::Rig& r, const Machine& m, std::size_t a, double x_start);
// Longest a cycle may run (machine time).
double time_bound(rig::Rig& r, const Machine& m, const CyclePlan& plan);

// The end of a cycle, the machine at rest.
void verdict(Watch& w, rig::Rig& r, const Machine& m, const Causes& causes, std::uint32_t cycles_before);

std::string alarm_list(std::uint32_t bits);

}  // namespace campaign
