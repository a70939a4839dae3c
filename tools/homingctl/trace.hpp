#pragma once
// The homing trace of one axis (FC 20 file = axis + 1, see server/trace.hpp):
// read in chunks (trace_file.cpp), cut to a time window, as CSV samples or
// JSON, and drawn as an SVG (trace_svg.cpp: position, velocity and sensor
// against time, phases shaded, the reference edge marked).
#include <cstdint>
#include <expected>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "connection.hpp"
#include "homing/phases.hpp"
#include "homing/alarms.hpp"
#include "homing/settings.hpp"

namespace homingctl {

struct TracePoint {
  std::uint32_t time_ms = 0;
  homing::Phase phase = homing::Phase::idle;
  double position_mm = 0;
  double velocity_mm_per_s = 0;
  bool sensor = false;
};

// The part of the cycle shown, in ms from the start of the trace.
struct TimeWindow {
  double from_ms = 0;
  double to_ms = 0;
};

struct Trace {
  std::size_t axis = 0;
  double interval_ms = 0;
  std::optional<std::uint32_t> edge_time_ms;
  double edge_position_mm = 0;
  homing::AlarmCode alarm = homing::AlarmCode::none;
  homing::Phase alarm_phase = homing::Phase::idle;
  std::uint32_t duration_ms = 0;
  std::vector<TracePoint> samples;
  std::optional<TimeWindow> window;  // set by window_trace: the samples are those inside it
  // The kind the axis moves with (homing::axis_kind of the module's settings,
  // set by `homingctl trace`); unset, a new module's kind of the axis.
  std::optional<homing::AxisKind> kind;

  // Where the recorded cycle ends (ms): its duration, or the last sample if later.
  double end_ms() const;
  // "mm" or "deg": the unit of the positions.
  std::string_view unit() const;
};

// Parses the words of a trace file (header + samples); throws std::runtime_error when malformed.
Trace parse_trace(std::size_t axis, const std::vector<std::uint16_t>& words);
// Reads the whole file over FC 20 (chunks of at most 120 records).
Trace read_trace(Connection& c, std::size_t axis);

// Why --from/--to cannot be a window of any trace (negative, not a number,
// not ending after it starts), or nothing.
std::optional<std::string> window_error(std::optional<double> from_s, std::optional<double> to_s);

// The samples from `from_s` to `to_s` (seconds from the start of the trace,
// both included; a missing end is the end of the trace), to zoom into a short
// phase. A window that is negative, empty or holds no sample is refused with
// a sentence naming --from / --to.
std::expected<Trace, std::string> window_trace(const Trace& t, std::optional<double> from_s,
                                               std::optional<double> to_s);

std::string trace_csv(const Trace& t);
nlohmann::json trace_json(const Trace& t);
// `alarm_text` is shown under the title when not empty.
std::string trace_svg(const Trace& t, const std::string& alarm_text);

}  // namespace homingctl
