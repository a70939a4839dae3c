#pragma once
// Inputs as the engine wants them. EdgeInput turns a line's kernel events
// (timestamps already on CLOCK_MONOTONIC) into timed transitions of one
// control period; LevelInput samples a level, optionally debounced.
#include <cstdint>
#include <expected>
#include <string>
#include <vector>

#include "homing/io.hpp"
#include "line_api.hpp"

namespace homing::gpiod {

class EdgeInput {
 public:
  EdgeInput(LineApi& lines, LineId line, bool level) : lines_(lines), line_(line), level_(level) {}

  // Drains the kernel's queue; timestamps are mapped onto CLOCK_MONOTONIC
  // with both clocks' readings taken just before.
  std::expected<void, std::string> poll(std::int64_t now_monotonic_ns, std::int64_t now_realtime_ns);

  // The transitions before end_ns, with times from start_ns; later ones stay
  // for the next period (the control loop may run several short periods at
  // once when it is late). Only changes of level count: a repeated event
  // type means its partner was lost, and the level is what matters.
  void take(std::int64_t start_ns, std::int64_t end_ns, bool rising_only, InputEdges& edges, bool& level);
  // Transitions left for a later period (after the end of the last one taken).
  bool has_pending() const { return !pending_.empty(); }

 private:
  struct Pending {
    std::int64_t time_ns;
    bool level;
  };
  LineApi& lines_;
  LineId line_;
  bool level_;  // after every transition taken so far
  std::vector<Pending> pending_;
};

class LevelInput {
 public:
  // events: the line was requested with its edges' events, only so that an
  // edge wakes an idle control loop; sample() discards them (the level read
  // after is what counts).
  LevelInput(LineApi& lines, LineId line, std::int64_t debounce_ns, bool level, bool events = false)
      : lines_(lines), line_(line), events_(events), debounce_ns_(debounce_ns), stable_(level), raw_(level) {}
  // The level at now_ns: a change counts once it has lasted debounce_ns.
  std::expected<bool, std::string> sample(std::int64_t now_ns);
  // A change waits for its debounce time: it counts at settles_at_ns().
  bool settling() const { return raw_ != stable_; }
  std::int64_t settles_at_ns() const { return raw_since_ns_ + debounce_ns_; }

 private:
  LineApi& lines_;
  LineId line_;
  bool events_;
  std::int64_t debounce_ns_;
  bool stable_;
  bool raw_;
  std::int64_t raw_since_ns_ = 0;
};

}  // namespace homing::gpiod
