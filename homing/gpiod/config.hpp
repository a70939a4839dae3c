#pragma once
// The [gpiod] table of homingd's config file: which GPIO line carries which
// signal, and the pulse generator's timing. See README.md for an example.
#include <array>
#include <cstdint>
#include <expected>
#include <optional>
#include <string>

#include "homing/axes.hpp"
#include "homing/settings.hpp"
#include "line_api.hpp"

namespace toml {
inline namespace v3 {
class table;
}
}  // namespace toml

namespace homing::gpiod {

struct AxisLines {
  bool configured = false;
  double steps_per_unit = 0;  // motor steps per mm (per degree on A B C); with step/dir only
  std::optional<LineSpec> step, dir, enable;            // outputs
  std::optional<LineSpec> push, commutator;             // outputs (pushing modes, gantry commutator)
  std::optional<LineSpec> home, index, drive_fault;     // inputs
  std::optional<LineSpec> stall;                        // input: the drive's stall output (hard-stop homing)
  // Drive-performed homing (axis.<a>.mode = drive): the request to the drive
  // (output) and its home done (input, a level).
  std::optional<LineSpec> home_request, home_done;
  // Locking indexer (axis.<a>.indexer_lock): the output that pulls the pin
  // out, and the input that reports it out.
  std::optional<LineSpec> unlock, unlocked;
  // End-of-travel limit switches (axis.<a>.limits_fitted; home_cam needs
  // them): inputs read as levels, polarity from axis.<a>.limits_nc.
  std::optional<LineSpec> limit_min, limit_max;
  // A step/dir output of its own. Without one the axis can only be an
  // external-commutator slave (moved by its master's output) or never move.
  bool has_output() const { return step.has_value(); }
};

struct BackendConfig {
  std::array<AxisLines, kAxisCount> axes{};
  std::optional<LineSpec> estop, drive_fault, start_button, homing_permit;  // inputs
  std::optional<LineSpec> homing_done_lamp;                                 // output
  std::int64_t tick_us = 10;          // pulse thread period; max step rate is 1/(2 tick)
  std::int64_t dir_setup_us = 5;      // direction stable before the next step edge
  std::int64_t input_debounce_ms = 10;  // start button and permit (sensors use the engine's debounce)
  std::int64_t playback_delay_us = 0;   // pulses this late after the engine's period start (see step_generator.hpp)
  int rt_priority = 0;                  // SCHED_FIFO priority of the pulse thread, 0 = normal
};

// origin names the file in errors ("config.toml: [gpiod.axes.X] step: ...").
std::expected<BackendConfig, std::string> parse_config(const toml::table& root, const std::string& origin);
std::expected<BackendConfig, std::string> load_config(const std::string& path);

// Whether this wiring can do what the settings ask (checked at start and on
// every settings write, since the [gpiod] table is read before the settings):
// an axis that can move (mode not disabled) needs a step/dir output of its
// own, unless it is an external-commutator slave; a commutator slave's master
// needs step/dir and a `commutator` line; an axis homing on a switch needs a
// `home` line (a commutator slave's switch is read on its master's); an axis
// with axis.<a>.indexer_lock needs its `unlock` and `unlocked` lines; one
// with axis.<a>.limits_fitted (home_cam) its `limit_min` and `limit_max`. The
// first problem in words, or nullopt.
std::optional<std::string> check_wiring(const BackendConfig& config, const homing::Settings& settings);

}  // namespace homing::gpiod
