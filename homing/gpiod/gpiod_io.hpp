#pragma once
// The real machine behind the control loop: step/dir/enable outputs, home and
// index sensors with kernel-timestamped edges, e-stop, drive fault, start
// button, homing permit and lamp, all through a LineApi (libgpiod on the
// cabinet, a fake chip in tests).
#include <array>
#include <cstdint>
#include <expected>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config.hpp"
#include "event_clock.hpp"
#include "homing/machine_io.hpp"
#include "inputs.hpp"
#include "line_api.hpp"
#include "pulse_thread.hpp"
#include "step_generator.hpp"

namespace homing::gpiod {

struct Clocks {
  std::function<std::int64_t()> monotonic_ns = monotonic_now_ns;
  std::function<std::int64_t()> realtime_ns = realtime_now_ns;
};

struct RunOptions {
  int control_period_us = 1000;
  bool start_pulse_thread = true;  // tests tick the generators themselves
  Clocks clocks{};
  std::function<void(const std::string&)> warn = [](const std::string&) {};
};

class GpiodIo final : public MachineIo {
 public:
  // Requests every configured line; the first failure is returned and the
  // lines already taken are released.
  static std::expected<std::unique_ptr<GpiodIo>, std::string> open(const BackendConfig& config,
                                                                  std::unique_ptr<LineApi> lines,
                                                                  RunOptions options);
  ~GpiodIo() override;

  // Moves the timeline on by the elapsed period (the outputs were already
  // applied).
  void advance(const Outputs& outputs, double dt_s) override;
  Inputs read() override;
  // Queues each axis's segment to start at the beginning of the period now
  // beginning (+ playback_delay_us, 0 by default) and sets enable, push,
  // commutator, the drive's home request, the indexer's unlock and the lamp.
  void apply(const Outputs& outputs) override;
  void shutdown() override;
  // Idle: nothing changes of itself but a debounced input about to count
  // (or an edge left for the next period). Every input line with events
  // wakes the loop on an edge.
  double quiet_for_s(const Outputs& outputs) const override;
  std::span<const int> event_fds() const override { return event_fds_; }

  // For tests and diagnostics (nullptr for an axis without step/dir).
  StepGenerator* generator(std::size_t axis) { return axes_[axis].generator.get(); }
  std::int64_t playback_delay_ns() const { return playback_delay_ns_; }
  std::int64_t period_start_ns() const { return period_start_ns_; }

 private:
  struct OutputLine {
    std::optional<LineId> id;
    bool value = false;
  };
  struct Axis {
    bool configured = false;
    std::unique_ptr<StepGenerator> generator;
    OutputLine enable, push, commutator, home_request, unlock;
    std::unique_ptr<EdgeInput> home, index;
    std::unique_ptr<LevelInput> drive_fault, stall, home_done, unlocked, limit_min, limit_max;
    std::string reported_failure;
  };

  GpiodIo(const BackendConfig& config, std::unique_ptr<LineApi> lines, RunOptions options);
  std::expected<void, std::string> request_all(const BackendConfig& config);
  void write(OutputLine& out, bool value);
  void input_failed(const std::string& message);
  // The line's event descriptor (if it has one) is among event_fds().
  void watch(LineId line);

  std::unique_ptr<LineApi> lines_;
  RunOptions options_;
  std::array<Axis, kAxisCount> axes_{};
  std::unique_ptr<LevelInput> estop_, drive_fault_, start_button_, homing_permit_;
  OutputLine lamp_;
  std::vector<int> event_fds_;
  std::unique_ptr<PulseThread> pulse_thread_;
  std::int64_t playback_delay_ns_ = 0;
  std::int64_t dir_setup_ns_ = 0;
  std::int64_t tick_ns_ = 0;
  std::int64_t input_debounce_ns_ = 0;
  int rt_priority_ = 0;

  // The elapsed control period on CLOCK_MONOTONIC: [start, end).
  bool anchored_ = false;
  std::int64_t period_start_ns_ = 0;
  std::int64_t period_end_ns_ = 0;
  bool input_fault_ = false;
  std::string last_input_error_;
  bool shut_down_ = false;
};

}  // namespace homing::gpiod
