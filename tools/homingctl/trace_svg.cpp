#include "trace_svg.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace homingctl {

namespace {

constexpr std::size_t kHeader = 10, kSample = 8;

std::uint32_t u32(const std::vector<std::uint16_t>& w, std::size_t at) {
  return (static_cast<std::uint32_t>(w[at]) << 16) | w[at + 1];
}
std::int32_t i32(const std::vector<std::uint16_t>& w, std::size_t at) { return static_cast<std::int32_t>(u32(w, at)); }

std::string xml_escape(std::string_view s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

// One colour per phase (value = register value).
std::string_view phase_colour(homing::Phase p) {
  static constexpr std::string_view k[] = {"#cccccc", "#e0e0e0", "#b3de69", "#80b1d3", "#fb8072", "#bc80bd",
                                           "#fdb462", "#ffed6f", "#8dd3c7", "#bebada", "#ccebc5", "#fccde5",
                                           "#d9d9d9", "#a6d854", "#e5c494", "#b3b3b3", "#ff7f00"};
  const auto i = static_cast<std::size_t>(p);
  return i < std::size(k) ? k[i] : "#999999";
}

// Round tick step for a span.
double tick_step(double span, int want) {
  if (span <= 0) return 1;
  const double raw = span / want;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * mag) return m * mag;
  return 10 * mag;
}

}  // namespace

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

std::string trace_svg(const Trace& t, const std::string& alarm_text) {
  const double W = 960, left = 80, right = 20, plot_w = W - left - right;
  const double top = alarm_text.empty() ? 50 : 70;
  const double ph = 150, gap = 30, sensor_h = 60;
  const double y_pos = top, y_vel = y_pos + ph + gap, y_sen = y_vel + ph + gap;
  const double legend_y = y_sen + sensor_h + 45;
  const double H = legend_y + 40;
  const auto unit = homing::axis_unit(t.axis);
  const char X = homing::kAxisUpper[t.axis];

  double t_end = t.duration_ms;
  if (!t.samples.empty()) t_end = std::max<double>(t_end, t.samples.back().time_ms);
  if (t_end <= 0) t_end = 1;
  auto tx = [&](double ms) { return left + plot_w * ms / t_end; };

  auto range = [&](auto get) {
    double lo = 0, hi = 0;
    bool first = true;
    for (const auto& s : t.samples) {
      const double v = get(s);
      lo = first ? v : std::min(lo, v);
      hi = first ? v : std::max(hi, v);
      first = false;
    }
    if (hi - lo < 1e-6) {
      lo -= 1;
      hi += 1;
    }
    const double pad = (hi - lo) * 0.05;
    return std::pair{lo - pad, hi + pad};
  };
  const auto [p_lo, p_hi] = range([](const TracePoint& s) { return s.position_mm; });
  const auto [v_lo, v_hi] = range([](const TracePoint& s) { return s.velocity_mm_per_s; });

  std::string o;
  o += fmt::format("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" viewBox=\"0 0 {:.0f} {:.0f}\" "
                   "font-family=\"sans-serif\" font-size=\"11\">\n",
                   W, H, W, H);
  o += fmt::format("<rect width=\"{:.0f}\" height=\"{:.0f}\" fill=\"white\"/>\n", W, H);
  o += fmt::format("<text id=\"title\" x=\"{:.0f}\" y=\"22\" font-size=\"15\" font-weight=\"bold\">Homing trace, axis {}: "
                   "{} samples every {:g} ms, cycle {:.3f} s{}</text>\n",
                   left, X, t.samples.size(), t.interval_ms, t.duration_ms / 1000.0,
                   t.alarm == homing::AlarmCode::none ? "" : fmt::format(", alarm {}", homing::alarm_name(t.alarm)));
  if (!alarm_text.empty())
    o += fmt::format("<text id=\"alarm\" x=\"{:.0f}\" y=\"44\" fill=\"#c00000\">{}</text>\n", left, xml_escape(alarm_text));

  // Phase bands over the three plots.
  o += "<g id=\"phases\">\n";
  std::vector<homing::Phase> seen;
  for (std::size_t i = 0; i < t.samples.size();) {
    std::size_t j = i;
    while (j + 1 < t.samples.size() && t.samples[j + 1].phase == t.samples[i].phase) ++j;
    const double x0 = tx(t.samples[i].time_ms);
    const double x1 = j + 1 < t.samples.size() ? tx(t.samples[j + 1].time_ms) : tx(t_end);
    const auto p = t.samples[i].phase;
    if (std::find(seen.begin(), seen.end(), p) == seen.end()) seen.push_back(p);
    o += fmt::format("<rect class=\"phase-band\" data-phase=\"{}\" x=\"{:.2f}\" y=\"{:.0f}\" width=\"{:.2f}\" height=\"{:.0f}\" "
                     "fill=\"{}\" fill-opacity=\"0.35\"><title>{} {}..{} ms</title></rect>\n",
                     homing::phase_name(p), x0, top, std::max(0.5, x1 - x0), y_sen + sensor_h - top, phase_colour(p),
                     homing::phase_name(p), t.samples[i].time_ms, j + 1 < t.samples.size() ? t.samples[j + 1].time_ms : static_cast<std::uint32_t>(t_end));
    i = j + 1;
  }
  o += "</g>\n";

  // One plot: frame, y ticks, polyline.
  auto plot = [&](std::string_view id, std::string_view label, double y0, double h, double lo, double hi, auto get,
                  std::string_view colour, bool step) {
    auto ty = [&](double v) { return y0 + h - h * (v - lo) / (hi - lo); };
    o += fmt::format("<g id=\"{}\">\n", id);
    o += fmt::format("<rect class=\"frame\" x=\"{:.0f}\" y=\"{:.0f}\" width=\"{:.0f}\" height=\"{:.0f}\" fill=\"none\" stroke=\"#444\"/>\n",
                     left, y0, plot_w, h);
    o += fmt::format("<text class=\"axis-label\" x=\"12\" y=\"{:.0f}\" transform=\"rotate(-90 12 {:.0f})\" text-anchor=\"middle\">{}</text>\n",
                     y0 + h / 2, y0 + h / 2, label);
    if (step) {
      for (int v = 0; v <= 1; ++v)
        o += fmt::format("<text class=\"tick\" x=\"{:.0f}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n", left - 6, ty(v) + 4,
                         v ? "active" : "off");
    } else {
      const double st = tick_step(hi - lo, 4);
      for (double v = std::ceil(lo / st) * st; v <= hi + 1e-9; v += st) {
        o += fmt::format("<line class=\"grid\" x1=\"{:.0f}\" x2=\"{:.0f}\" y1=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>\n", left,
                         left + plot_w, ty(v), ty(v));
        o += fmt::format("<text class=\"tick\" x=\"{:.0f}\" y=\"{:.1f}\" text-anchor=\"end\">{:g}</text>\n", left - 6, ty(v) + 4,
                         std::abs(v) < st * 1e-6 ? 0.0 : v);
      }
    }
    std::string pts;
    double prev_y = 0;
    bool first = true;
    for (const auto& s : t.samples) {
      const double x = tx(s.time_ms), y = ty(get(s));
      if (step && !first) pts += fmt::format("{:.2f},{:.2f} ", x, prev_y);
      pts += fmt::format("{:.2f},{:.2f} ", x, y);
      prev_y = y;
      first = false;
    }
    o += fmt::format("<polyline class=\"trace\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" points=\"{}\"/>\n", colour, pts);
    o += "</g>\n";
  };
  plot("position", fmt::format("position ({})", unit), y_pos, ph, p_lo, p_hi,
       [](const TracePoint& s) { return s.position_mm; }, "#1f4e9c", false);
  plot("velocity", fmt::format("velocity ({}/s)", unit), y_vel, ph, v_lo, v_hi,
       [](const TracePoint& s) { return s.velocity_mm_per_s; }, "#2a8c3a", false);
  plot("sensor", "sensor", y_sen, sensor_h, -0.2, 1.2, [](const TracePoint& s) { return s.sensor ? 1.0 : 0.0; },
       "#b03030", true);

  // Shared time axis under the sensor plot.
  o += "<g id=\"time-axis\">\n";
  const double base = y_sen + sensor_h;
  const double st = tick_step(t_end, 8);
  for (double v = 0; v <= t_end + 1e-9; v += st) {
    o += fmt::format("<line x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{:.0f}\" y2=\"{:.0f}\" stroke=\"#444\"/>\n", tx(v), tx(v), base, base + 5);
    o += fmt::format("<text class=\"tick\" x=\"{:.1f}\" y=\"{:.0f}\" text-anchor=\"middle\">{:g}</text>\n", tx(v), base + 17, v);
  }
  o += fmt::format("<text class=\"axis-label\" x=\"{:.0f}\" y=\"{:.0f}\" text-anchor=\"middle\">time (ms)</text>\n",
                   left + plot_w / 2, base + 32);
  o += "</g>\n";

  // The reference edge: where the homing found its reference.
  if (t.edge_time_ms) {
    const double x = tx(*t.edge_time_ms);
    o += "<g id=\"reference-edge\">\n";
    o += fmt::format("<line x1=\"{:.2f}\" x2=\"{:.2f}\" y1=\"{:.0f}\" y2=\"{:.0f}\" stroke=\"#d00000\" stroke-width=\"1.5\" "
                     "stroke-dasharray=\"5,3\"/>\n",
                     x, x, top, y_sen + sensor_h);
    o += fmt::format("<text x=\"{:.2f}\" y=\"{:.0f}\" fill=\"#d00000\">reference edge {:.3f} {} at {} ms</text>\n", x + 4,
                     top + 12, t.edge_position_mm, unit, *t.edge_time_ms);
    o += "</g>\n";
  }

  // Legend of the phases shown.
  o += "<g id=\"legend\">\n";
  double lx = left;
  for (const auto p : seen) {
    const auto name = homing::phase_name(p);
    o += fmt::format("<rect x=\"{:.0f}\" y=\"{:.0f}\" width=\"12\" height=\"12\" fill=\"{}\" fill-opacity=\"0.6\" stroke=\"#888\"/>\n",
                     lx, legend_y, phase_colour(p));
    o += fmt::format("<text class=\"legend-phase\" x=\"{:.0f}\" y=\"{:.0f}\">{}</text>\n", lx + 16, legend_y + 10, name);
    lx += 30 + 7.0 * static_cast<double>(name.size());
  }
  if (t.edge_time_ms) {
    o += fmt::format("<line x1=\"{:.0f}\" x2=\"{:.0f}\" y1=\"{:.0f}\" y2=\"{:.0f}\" stroke=\"#d00000\" stroke-dasharray=\"5,3\"/>\n",
                     lx, lx + 16, legend_y + 6, legend_y + 6);
    o += fmt::format("<text x=\"{:.0f}\" y=\"{:.0f}\">reference edge</text>\n", lx + 20, legend_y + 10);
  }
  o += "</g>\n</svg>\n";
  return o;
}

}  // namespace homingctl
