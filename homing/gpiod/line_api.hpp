#pragma once
// The narrow seam between the GPIO backend and libgpiod. The backend only
// ever talks to a LineApi: the real one (gpiod_lines.hpp) wraps libgpiod v1,
// tests substitute a fake chip that records output edges and plays input
// events. Handles are small integers owned by the LineApi, so no raw
// gpiod_chip*/gpiod_line* leaves the implementation.
#include <cstddef>
#include <cstdint>
#include <expected>
#include <span>
#include <string>
#include <variant>

namespace homing::gpiod {

enum class Bias : std::uint8_t { as_is, disable, pull_up, pull_down };

// Where one signal is wired: a chip (name, path, label or number, as
// gpiod_chip_open_lookup accepts; empty = search every chip for a line name)
// and a line (offset on that chip, or the line's name).
struct LineSpec {
  std::string role;  // what the line is for, e.g. "X.step"; named in every error
  std::string chip;
  std::variant<unsigned, std::string> line = 0u;
  bool active_low = false;
  Bias bias = Bias::as_is;
};

// "X.step (gpiochip0 line 23)": how errors and logs name a line.
std::string describe(const LineSpec& spec);

using LineId = int;

struct LineEvent {
  std::int64_t timestamp_ns = 0;  // kernel timestamp, in the kernel's event clock
  bool rising = false;            // logical level after the event (active-low applied)
};

class LineApi {
 public:
  virtual ~LineApi() = default;
  // Errors are messages a technician can act on; they name the role, chip and line.
  virtual std::expected<LineId, std::string> request_output(const LineSpec& spec, bool initial) = 0;
  // A level input, sampled with get_value.
  virtual std::expected<LineId, std::string> request_input(const LineSpec& spec) = 0;
  // An input whose both edges are queued by the kernel with timestamps.
  virtual std::expected<LineId, std::string> request_input_events(const LineSpec& spec) = 0;
  virtual std::expected<void, std::string> set_value(LineId line, bool value) = 0;
  virtual std::expected<bool, std::string> get_value(LineId line) = 0;
  // Never blocks: returns the events queued so far (at most out.size()).
  virtual std::expected<std::size_t, std::string> read_events(LineId line, std::span<LineEvent> out) = 0;
  // A descriptor readable while the line has events queued (a line requested
  // with request_input_events), -1 for any other: the control loop waits on
  // it while idle, so an input edge wakes it.
  virtual int event_fd(LineId line) = 0;
};

}  // namespace homing::gpiod
