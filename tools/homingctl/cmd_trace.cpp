// trace: the last homing cycle of an axis (FC 20) as a summary, SVG, CSV or JSON.
#include <fmt/format.h>

#include <optional>

#include "actions.hpp"
#include "homing/gantry.hpp"
#include "cli.hpp"
#include "settings_io.hpp"
#include "status_view.hpp"
#include "trace.hpp"

namespace homingctl {

namespace {

struct TraceOptions {
  std::string axis, svg_file, csv_file;
  std::optional<double> from_s, to_s;  // the window, seconds from the start of the trace
};

// read_trace(), with why it cannot work when the link is RTU.
Trace read_trace_or_explain(Connection& c, std::size_t axis) {
  try {
    return read_trace(c, axis);
  } catch (const LinkError& e) {
    if (!c.is_rtu()) throw;
    throw LinkError(fmt::format("{}\n(homingd before 0.1.0 serves the traces (function 20) over Modbus TCP "
                                "only: use --tcp)", e.what()));
  }
}

// The alarm that ended the traced cycle, in words ("" when none).
std::string trace_alarm(Connection& c, std::size_t axis, const Trace& t) {
  if (t.alarm == homing::AlarmCode::none) return {};
  AxisView v;
  v.alarm = t.alarm;
  v.alarm_phase = t.alarm_phase;
  return alarm_text(axis, v, read_settings(c));
}

// The SVG and CSV files asked for; false when one could not be written (said on stderr).
bool write_trace_files(const TraceOptions& o, const Trace& t, const std::string& alarm) {
  if (!o.svg_file.empty())
    if (auto w = write_file_atomically(o.svg_file, trace_svg(t, alarm)); !w) {
      fmt::print(stderr, "homingctl trace: {}\n", w.error());
      return false;
    }
  if (!o.csv_file.empty()) {
    if (o.csv_file == "-") fmt::print("{}", trace_csv(t));
    else if (auto w = write_file_atomically(o.csv_file, trace_csv(t)); !w) {
      fmt::print(stderr, "homingctl trace: {}\n", w.error());
      return false;
    }
  }
  return true;
}

void print_summary(std::size_t axis, const Trace& t, const std::string& alarm, const TraceOptions& o) {
  if (t.window)
    fmt::print("{}: {} samples every {:g} ms from {:g} s to {:g} s of a {:.3f} s cycle", homing::kAxisUpper[axis],
               t.samples.size(), t.interval_ms, t.window->from_ms / 1000.0, t.window->to_ms / 1000.0,
               t.duration_ms / 1000.0);
  else
    fmt::print("{}: {} samples every {:g} ms over {:.3f} s", homing::kAxisUpper[axis], t.samples.size(), t.interval_ms,
               t.duration_ms / 1000.0);
  if (t.edge_time_ms) fmt::print(", reference edge at {} ms ({:.3f} {})", *t.edge_time_ms, t.edge_position_mm,
                                 t.unit());
  fmt::print("{}\n", alarm.empty() ? "" : "\n  alarm: " + alarm);
  if (!o.svg_file.empty()) fmt::print("drawn to {}\n", o.svg_file);
}

int trace(Context& ctx, const TraceOptions& o) {
  const int index = axis_index(o.axis);
  if (index < 0) throw Usage(fmt::format("trace: '{}' is not an axis (x, y, z, a, b, c)", o.axis));
  const auto axis = static_cast<std::size_t>(index);
  if (auto bad = window_error(o.from_s, o.to_s)) throw Usage(fmt::format("trace: {}", *bad));
  Connection& c = ctx.connection();
  Trace whole = read_trace_or_explain(c, axis);
  // The unit shows in the SVG and the summary only (the CSV and JSON name no
  // unit): the settings are read for those alone.
  if (!o.svg_file.empty() || (!ctx.json && o.csv_file != "-")) whole.kind = homing::axis_kind(read_settings(c), axis);
  if (whole.samples.empty()) {
    fmt::print(stderr, "no trace for {}: the axis has not taken part in a homing cycle since homingd started\n",
               homing::kAxisUpper[axis]);
    return kFailed;
  }
  auto windowed = o.from_s || o.to_s ? window_trace(whole, o.from_s, o.to_s) : whole;
  if (!windowed) throw Usage(fmt::format("trace: {}", windowed.error()));
  const Trace& t = *windowed;
  const std::string alarm = trace_alarm(c, axis, t);
  if (!write_trace_files(o, t, alarm)) return kFailed;
  if (ctx.json) {
    auto j = trace_json(t);
    if (!alarm.empty()) j["alarm"]["text"] = alarm;
    print_json(j);
  } else if (o.csv_file != "-") {
    print_summary(axis, t, alarm, o);
  }
  return kOk;
}

}  // namespace

void add_trace_command(Commands& commands) {
  auto o = std::make_shared<TraceOptions>();
  auto* sub = commands.add("trace", "the last homing cycle of an axis (FC 20): summary, --svg FILE, --csv FILE|-, --from/--to S to zoom in",
                           [o](Context& ctx) { return trace(ctx, *o); });
  sub->add_option("axis", o->axis, "x y z a b c")->required();
  sub->add_option("--svg", o->svg_file, "draw position, velocity and sensor against time");
  sub->add_option("--csv", o->csv_file, "the samples as CSV ('-' = stdout)");
  sub->add_option("--from", o->from_s, "show from this time on (seconds from the start of the trace)");
  sub->add_option("--to", o->to_s, "show up to this time (seconds from the start of the trace)");
}

}  // namespace homingctl
