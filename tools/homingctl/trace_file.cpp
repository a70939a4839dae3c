// The trace file of an axis: parsed from its FC 20 words, cut to a window,
// written as CSV and JSON.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "trace.hpp"

namespace homingctl {

namespace {

constexpr std::size_t kHeader = 10, kSample = 8;

std::uint32_t u32(const std::vector<std::uint16_t>& w, std::size_t at) {
  return (static_cast<std::uint32_t>(w[at]) << 16) | w[at + 1];
}
std::int32_t i32(const std::vector<std::uint16_t>& w, std::size_t at) { return static_cast<std::int32_t>(u32(w, at)); }

}  // namespace

std::string_view Trace::unit() const { return homing::unit_of(kind.value_or(homing::default_kind(axis))); }

double Trace::end_ms() const {
  double end = duration_ms;
  if (!samples.empty()) end = std::max<double>(end, samples.back().time_ms);
  return end;
}

Trace parse_trace(std::size_t axis, const std::vector<std::uint16_t>& w) {
  if (w.size() < kHeader) throw std::runtime_error("trace file shorter than its header");
  Trace t;
  t.axis = axis;
  const std::size_t count = w[0];
  if (w.size() < kHeader + kSample * count)
    throw std::runtime_error(fmt::format("trace file has {} words, its header announces {} samples", w.size(), count));
  t.interval_ms = w[1] / 10.0;
  if (const auto e = u32(w, 2); e != 0xFFFFFFFFu) t.edge_time_ms = e;
  t.edge_position_mm = i32(w, 4) / 1000.0;
  t.alarm = static_cast<homing::AlarmCode>(w[6]);
  t.alarm_phase = static_cast<homing::Phase>(w[7]);
  t.duration_ms = u32(w, 8);
  t.samples.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t at = kHeader + kSample * i;
    t.samples.push_back(TracePoint{u32(w, at), static_cast<homing::Phase>(w[at + 2]), i32(w, at + 3) / 1000.0,
                                   i32(w, at + 5) / 1000.0, w[at + 7] != 0});
  }
  return t;
}

Trace read_trace(Connection& c, std::size_t axis) {
  const int file = static_cast<int>(axis) + 1;
  std::vector<std::uint16_t> words = c.read_file_record(file, 0, static_cast<int>(kHeader));
  const std::size_t total = kHeader + kSample * std::size_t{words[0]};
  while (words.size() < total) {
    const int n = static_cast<int>(std::min<std::size_t>(120, total - words.size()));
    const auto part = c.read_file_record(file, static_cast<int>(words.size()), n);
    words.insert(words.end(), part.begin(), part.end());
  }
  return parse_trace(axis, words);
}

std::optional<std::string> window_error(std::optional<double> from_s, std::optional<double> to_s) {
  if (from_s && !(std::isfinite(*from_s) && *from_s >= 0))
    return fmt::format("--from {:g}: give the start of the window in seconds from the start of the trace, 0 or more",
                       *from_s);
  if (to_s && !(std::isfinite(*to_s) && *to_s >= 0))
    return fmt::format("--to {:g}: give the end of the window in seconds from the start of the trace, after --from",
                       *to_s);
  if (to_s && *to_s <= from_s.value_or(0.0))
    return fmt::format("--from {:g} is not before --to {:g}: the window must end after it starts (seconds from the "
                       "start of the trace)",
                       from_s.value_or(0.0), *to_s);
  return std::nullopt;
}

std::expected<Trace, std::string> window_trace(const Trace& t, std::optional<double> from_s,
                                               std::optional<double> to_s) {
  if (auto bad = window_error(from_s, to_s)) return std::unexpected(*bad);
  const double end_s = t.end_ms() / 1000.0;
  const double from = from_s.value_or(0.0);
  if (from > end_s)
    return std::unexpected(fmt::format("--from {:g}: the trace of {} ends at {:.3f} s", from,
                                       homing::kAxisUpper[t.axis], end_s));
  Trace out = t;
  out.window = TimeWindow{from * 1000.0, std::min(to_s.value_or(end_s), end_s) * 1000.0};
  std::erase_if(out.samples, [&](const TracePoint& s) {
    return s.time_ms < out.window->from_ms || s.time_ms > out.window->to_ms;
  });
  if (out.samples.empty())
    return std::unexpected(fmt::format("no sample of {} between --from {:g} and --to {:g} s (one every {:g} ms): "
                                       "widen the window",
                                       homing::kAxisUpper[t.axis], from, out.window->to_ms / 1000.0, t.interval_ms));
  return out;
}

std::string trace_csv(const Trace& t) {
  std::string out = "time_ms,phase,position_mm,velocity_mm_per_s,sensor\n";
  for (const auto& s : t.samples)
    out += fmt::format("{},{},{:.3f},{:.3f},{}\n", s.time_ms, homing::phase_name(s.phase), s.position_mm,
                       s.velocity_mm_per_s, s.sensor ? 1 : 0);
  return out;
}

nlohmann::json trace_json(const Trace& t) {
  nlohmann::json j;
  j["axis"] = std::string(homing::kAxisLetters[t.axis]);
  j["interval_ms"] = t.interval_ms;
  j["duration_ms"] = t.duration_ms;
  j["window"] = t.window ? nlohmann::json{{"from_s", t.window->from_ms / 1000.0}, {"to_s", t.window->to_ms / 1000.0}}
                         : nlohmann::json(nullptr);
  j["reference_edge"] = t.edge_time_ms ? nlohmann::json{{"time_ms", *t.edge_time_ms}, {"position", t.edge_position_mm}}
                                       : nlohmann::json(nullptr);
  j["alarm"] = t.alarm == homing::AlarmCode::none
                   ? nlohmann::json(nullptr)
                   : nlohmann::json{{"name", std::string(homing::alarm_name(t.alarm))},
                                    {"phase", std::string(homing::phase_name(t.alarm_phase))}};
  j["samples"] = nlohmann::json::array();
  for (const auto& s : t.samples)
    j["samples"].push_back({s.time_ms, std::string(homing::phase_name(s.phase)), s.position_mm, s.velocity_mm_per_s,
                            s.sensor ? 1 : 0});
  return j;
}

}  // namespace homingctl
