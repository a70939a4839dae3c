#pragma once
// One run of the campaign: a generated machine, powered up, homed, and put
// through random acts (faults, aborts, resets, re-homes, jogs, moves, lost
// steps, a hard-limit trip), every period checked by the Watch.
#include <cstdint>
#include <memory>
#include <sstream>
#include <string>

#include "dice.hpp"
#include "machine.hpp"
#include "verdict.hpp"
#include "watch.hpp"

namespace campaign {

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
};

class Run {
 public:
  explicit Run(std::uint64_t seed);
  Outcome run();

 private:
  bool ok() const { return !w_->failed(); }
  void step() { r_.step(); }
  void settle(double max_s = 10);
  void say(const std::string& what);
  void power_up();
  bool cycle(bool all, AxisMask mask, std::vector<Event> events, bool by_button);
  void apply(const Event& e, Causes& causes);
  void recover();
  void jog_invalid_slave();
  void put_back(AxisMask mask);
  void exercise_motion();
  void hard_limit_recovery();
  void lost_steps();
  std::vector<Event> random_events(const CyclePlan& plan, double estimate);
  void follow_ups();
  bool homed_axis(std::size_t a) const;

  Machine m_;
  rig::Rig r_;
  Dice d_;
  Dice periods_;
  std::unique_ptr<Watch> w_;
  std::ostringstream log_;
  bool comm_lost_ = false;
  AxisMask encoder_invalid_ = 0;
  bool ever_homed_ = false;
  double last_cycle_s_ = 1;
};

Outcome run_seed(std::uint64_t seed);
// A failed run told for a reader: the failure, how to replay it, the machine, the script.
std::string report(const Outcome& o, const char* test_name);

}  // namespace campaign
