#pragma once
// What the settings imply before anything moves: per axis the stop distance
// against its limit, the engine's own check, an expected cycle time, and
// warnings about combinations that pass the check but are risky.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "homing/settings.hpp"

namespace homingctl {

struct TriggerCam {
  double min_mm = 0, max_mm = 0, hysteresis_mm = 0;  // from the simulator unit, when there is one
  // Its end-of-travel limit switches (the defaults lie beyond any stop).
  double limit_min_mm = -1e9, limit_max_mm = 1e9;
};

struct AxisCheck {
  std::size_t axis = 0;
  bool enabled = false;
  std::string unit;                // of the kind the axis moves with: "mm" or "deg"
  double stop_distance_mm = 0;     // seek_stop_distance_mm
  double max_stop_distance_mm = 0;
  std::optional<std::string> fault;  // describe_fault: homing will be refused
  double seek_worst_s = 0;           // over max_seek_travel (a home cam's: out to the limit switch and back)
  double after_trigger_s = 0;        // stop, back-off, re-approach, index, latch, pull-off, final move
  // Limit switches fitted: the stop past one from the faster of seek and jog
  // feedrate (limit_stop_distance_mm) against limit_overtravel.
  bool limits = false;
  double limit_stop_distance_mm = 0, limit_overtravel_mm = 0;
  std::vector<std::pair<std::string, double>> phases;  // phase name, seconds (estimate)
  std::vector<std::string> signals;  // what its method needs wired (kSignalInfo names), its stop detection included
  std::string stop_detection;        // how a method that pushes to a stop tells it (stall_detect); "" otherwise
  double max_following_error_mm = 0;  // with stop_detection following_error
  std::vector<std::string> warnings;
};

struct CheckReport {
  std::vector<AxisCheck> axes;
  double cycle_worst_s = 0;  // the sequence, steps one after the other, worst-case seeks
  std::vector<std::string> warnings;  // not tied to one axis
  bool ok() const;
};

CheckReport check_settings(const homing::Settings& s, const std::array<std::optional<TriggerCam>, homing::kAxisCount>& cams);
std::string render_check(const CheckReport& r);
nlohmann::json check_json(const CheckReport& r);

}  // namespace homingctl
