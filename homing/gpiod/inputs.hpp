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
  LevelInput(LineApi& lines, LineId line, std::int64_t debounce_ns, bool level)
      : lines_(lines), line_(line), debounce_ns_(debounce_ns), stable_(level), raw_(level) {}
  // The level at now_ns: a change counts once it has lasted debounce_ns.
  std::expected<bool, std::string> sample(std::int64_t now_ns);

 private:
  LineApi& lines_;
  LineId line_;
  std::int64_t debounce_ns_;
  bool stable_;
  bool raw_;
  std::int64_t raw_since_ns_ = 0;
};

}  // namespace homing::gpiod
