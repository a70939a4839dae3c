#pragma once
// Commands that move the machine: write the coil, see whether the module took
// it (status.last_command_result), wait for the outcome while keeping the
// watchdog's heartbeat alive, and say what went wrong in words.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "connection.hpp"

namespace homingctl {

struct ActionOptions {
  bool wait = true;
  double timeout_s = 300;
  double poll_s = 0.1;
};

struct ActionResult {
  int exit_code = 0;     // 0 ok, 1 failed (refused, alarm)
  std::string message;   // for people
  nlohmann::json json;   // for --json
};

// What `homingctl home` was asked to home: everything, or the named axes.
struct HomeTargets {
  bool all = true;
  std::uint8_t axes = 0;  // bit 0 = X
};
// `targets`: empty or "all" -> home-all; else axis letters. Throws
// std::invalid_argument naming a word that is not an axis (before any I/O).
HomeTargets home_targets(const std::vector<std::string>& targets);
// Home-all writes cmd.home_all; named axes write their mask to cmd.home_axes,
// so they home in one cycle (in sequence-step order, with gantry partners).
ActionResult home(Connection& c, const HomeTargets& targets, const ActionOptions& o);
ActionResult abort_motion(Connection& c, const ActionOptions& o);
ActionResult reset_alarm(Connection& c, const ActionOptions& o);
// Holds the jog coil for `ms` (refreshing the heartbeat), then releases it.
ActionResult jog(Connection& c, const std::string& axis, int direction, int ms, const ActionOptions& o);
ActionResult move(Connection& c, const std::string& axis, const std::string& target, const ActionOptions& o);
// cmd.refcheck.<a>: the reference check after a restart; ok when the axis
// ends homed by it (trust reference_checked), else refused with the figure.
ActionResult refcheck(Connection& c, const std::string& axis, const ActionOptions& o);
// cmd.unhome.<a>: forget an axis's reference (and its gantry partner's)
// without moving, e.g. after squaring a gantry by hand.
ActionResult unhome(Connection& c, const std::string& axis, const ActionOptions& o);
// cmd.measure.<a>: homes the axis, measures its travel to the opposite end and
// prints the figures; with apply, writes soft_limit_min/max and
// max_seek_travel through the settings path (checked, audited).
ActionResult measure(Connection& c, const std::string& axis, bool apply, const ActionOptions& o);

// Axis index of "x".."c" (case-insensitive) or -1.
int axis_index(std::string_view letter);
// axis >= 0: that axis's letter where the text says <a>.
std::string command_result_text(int result, int axis = -1);

}  // namespace homingctl
