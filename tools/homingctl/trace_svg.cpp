// The trace of an axis drawn as an SVG: position, velocity and sensor against
// time, phases shaded, the reference edge marked. Every label is measured
// (text_fit.hpp) and placed where it fits: long titles and alarm texts wrap,
// the left margin takes the widest tick label, time ticks are spaced for their
// labels, the legend starts new rows, the edge label turns left at the right end.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "svg_parts.hpp"
#include "text_fit.hpp"
#include "trace.hpp"

namespace homingctl {

namespace {

constexpr double kWidth = 960, kMargin = 20, kMinLeft = 80;
constexpr double kFont = 11, kTitleFont = 15;
constexpr double kLine = 15, kTitleLine = 19, kLegendRow = 20;
constexpr double kPlotH = 150, kGap = 30, kSensorH = 60;
constexpr double kAxisLabelX = 12;  // the rotated axis labels' baseline

// One colour per phase (value = register value).
std::string_view phase_colour(homing::Phase p) {
  static constexpr std::string_view k[] = {"#cccccc", "#e0e0e0", "#b3de69", "#80b1d3", "#fb8072", "#bc80bd",
                                           "#fdb462", "#ffed6f", "#8dd3c7", "#bebada", "#ccebc5", "#fccde5",
                                           "#d9d9d9", "#a6d854", "#e5c494", "#b3b3b3", "#ff7f00"};
  const auto i = static_cast<std::size_t>(p);
  return i < std::size(k) ? k[i] : "#999999";
}

double widest(const std::vector<Tick>& ts) { return homingctl::widest(ts, kFont); }

// The values plotted: a range padded by 5 %, never empty.
template <class Get>
std::pair<double, double> value_range(const Trace& t, Get get) {
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
  return {lo - pad, hi + pad};
}

struct LegendItem {
  std::string label;
  std::string_view colour;  // "" = the reference edge's dashed line
  double x = 0, y = 0;
};

class Drawing {
 public:
  Drawing(const Trace& t, const std::string& alarm) : t_(t) {
    t0_ = t.window ? t.window->from_ms : 0.0;
    t1_ = t.window ? t.window->to_ms : t.end_ms();
    if (t1_ <= t0_) t1_ = t0_ + 1;
    std::tie(p_lo_, p_hi_) = value_range(t, [](const TracePoint& s) { return s.position_mm; });
    std::tie(v_lo_, v_hi_) = value_range(t, [](const TracePoint& s) { return s.velocity_mm_per_s; });
    p_ticks_ = ticks(p_lo_, p_hi_, tick_step(p_hi_ - p_lo_, 4));
    v_ticks_ = ticks(v_lo_, v_hi_, tick_step(v_hi_ - v_lo_, 4));
    // The tick labels end 6 px left of the plots and clear the rotated axis label.
    left_ = std::max(kMinLeft, std::ceil(std::max(widest(p_ticks_), widest(v_ticks_)) + 6 + kAxisLabelX + 0.2 * kFont + 6));
    plot_w_ = kWidth - left_ - kMargin;
    title_ = wrap_text(title_text(), kWidth - 2 * kMargin, kTitleFont, true);
    if (!alarm.empty()) alarm_ = wrap_text(alarm, kWidth - 2 * kMargin, kFont);
    const double last_text = 22 + kTitleLine * static_cast<double>(title_.size() - 1) +
                             (alarm_.empty() ? 0 : 6 + kLine * static_cast<double>(alarm_.size()));
    top_ = last_text + 26;
    y_vel_ = top_ + kPlotH + kGap;
    y_sen_ = y_vel_ + kPlotH + kGap;
    place_legend(y_sen_ + kSensorH + 45);
  }

  std::string svg() {
    o_ += fmt::format("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" viewBox=\"0 0 {:.0f} "
                      "{:.0f}\" font-family=\"DejaVu Sans, sans-serif\" font-size=\"{:g}\">\n",
                      kWidth, height_, kWidth, height_, kFont);
    o_ += fmt::format("<rect width=\"{:.0f}\" height=\"{:.0f}\" fill=\"white\"/>\n", kWidth, height_);
    heading();
    phases();
    const auto unit = t_.unit();
    plot("position", fmt::format("position ({})", unit), top_, kPlotH, p_lo_, p_hi_, p_ticks_,
         [](const TracePoint& s) { return s.position_mm; }, "#1f4e9c", false);
    plot("velocity", fmt::format("velocity ({}/s)", unit), y_vel_, kPlotH, v_lo_, v_hi_, v_ticks_,
         [](const TracePoint& s) { return s.velocity_mm_per_s; }, "#2a8c3a", false);
    plot("sensor", "sensor", y_sen_, kSensorH, -0.2, 1.2, {{0, "off"}, {1, "active"}},
         [](const TracePoint& s) { return s.sensor ? 1.0 : 0.0; }, "#b03030", true);
    time_axis();
    reference_edge();
    legend();
    o_ += "</svg>\n";
    return std::move(o_);
  }

 private:
  double tx(double ms) const { return left_ + plot_w_ * (ms - t0_) / (t1_ - t0_); }
  bool edge_shown() const { return t_.edge_time_ms && *t_.edge_time_ms >= t0_ && *t_.edge_time_ms <= t1_; }

  std::string title_text() const {
    std::string s = fmt::format("Homing trace, axis {}: {} samples every {:g} ms, cycle {:.3f} s",
                                homing::kAxisUpper[t_.axis], t_.samples.size(), t_.interval_ms, t_.duration_ms / 1000.0);
    if (t_.alarm != homing::AlarmCode::none) s += fmt::format(", alarm {}", homing::alarm_name(t_.alarm));
    if (t_.window) s += fmt::format(", shown {:g} s to {:g} s", t0_ / 1000.0, t1_ / 1000.0);
    return s;
  }

  void heading() {
    o_ += "<g id=\"title\">\n";
    for (std::size_t i = 0; i < title_.size(); ++i)
      o_ += fmt::format("<text x=\"{:.0f}\" y=\"{:.0f}\" font-size=\"{:g}\" font-weight=\"bold\">{}</text>\n", kMargin,
                        22 + kTitleLine * static_cast<double>(i), kTitleFont, xml_escape(title_[i]));
    o_ += "</g>\n";
    if (alarm_.empty()) return;
    const double y0 = 22 + kTitleLine * static_cast<double>(title_.size() - 1) + 6 + kLine;
    o_ += "<g id=\"alarm\" fill=\"#c00000\">\n";
    for (std::size_t i = 0; i < alarm_.size(); ++i)
      o_ += fmt::format("<text x=\"{:.0f}\" y=\"{:.0f}\">{}</text>\n", kMargin, y0 + kLine * static_cast<double>(i),
                        xml_escape(alarm_[i]));
    o_ += "</g>\n";
  }

  // Phase bands over the three plots, cut at the window.
  void phases() {
    o_ += "<g id=\"phases\">\n";
    const auto& ss = t_.samples;
    for (std::size_t i = 0; i < ss.size();) {
      std::size_t j = i;
      while (j + 1 < ss.size() && ss[j + 1].phase == ss[i].phase) ++j;
      const double from = ss[i].time_ms, to = j + 1 < ss.size() ? ss[j + 1].time_ms : t1_;
      const double x0 = tx(std::max(from, t0_)), x1 = tx(std::min(to, t1_));
      const auto p = ss[i].phase;
      o_ += fmt::format("<rect class=\"phase-band\" data-phase=\"{}\" x=\"{:.2f}\" y=\"{:.0f}\" width=\"{:.2f}\" "
                        "height=\"{:.0f}\" fill=\"{}\" fill-opacity=\"0.35\"><title>{} {:g}..{:g} ms</title></rect>\n",
                        homing::phase_name(p), x0, top_, std::max(0.5, x1 - x0), y_sen_ + kSensorH - top_,
                        phase_colour(p), homing::phase_name(p), from, to);
      i = j + 1;
    }
    o_ += "</g>\n";
  }

  // One plot: frame, y ticks, polyline (a step line for the sensor).
  template <class Get>
  void plot(std::string_view id, std::string_view label, double y0, double h, double lo, double hi,
            const std::vector<Tick>& ts, Get get, std::string_view colour, bool step) {
    auto ty = [&](double v) { return y0 + h - h * (v - lo) / (hi - lo); };
    o_ += fmt::format("<g id=\"{}\">\n", id);
    o_ += fmt::format("<rect class=\"frame\" x=\"{:.0f}\" y=\"{:.0f}\" width=\"{:.0f}\" height=\"{:.0f}\" fill=\"none\" "
                      "stroke=\"#444\"/>\n",
                      left_, y0, plot_w_, h);
    o_ += fmt::format("<text class=\"axis-label\" x=\"{:g}\" y=\"{:.0f}\" transform=\"rotate(-90 {:g} {:.0f})\" "
                      "text-anchor=\"middle\">{}</text>\n",
                      kAxisLabelX, y0 + h / 2, kAxisLabelX, y0 + h / 2, label);
    for (const auto& tick : ts) {
      if (!step)
        o_ += fmt::format("<line class=\"grid\" x1=\"{:.0f}\" x2=\"{:.0f}\" y1=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>\n",
                          left_, left_ + plot_w_, ty(tick.value), ty(tick.value));
      o_ += fmt::format("<text class=\"tick\" x=\"{:.0f}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n", left_ - 6,
                        ty(tick.value) + 4, tick.text);
    }
    std::string pts;
    double prev_y = 0;
    bool first = true;
    for (const auto& s : t_.samples) {
      const double x = tx(s.time_ms), y = ty(get(s));
      if (step && !first) pts += fmt::format("{:.2f},{:.2f} ", x, prev_y);
      pts += fmt::format("{:.2f},{:.2f} ", x, y);
      prev_y = y;
      first = false;
    }
    o_ += fmt::format("<polyline class=\"trace\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" points=\"{}\"/>\n",
                      colour, pts);
    o_ += "</g>\n";
  }

  // Shared time axis under the sensor plot; the step grows until the widest
  // label fits between two ticks.
  void time_axis() {
    const double span = t1_ - t0_;
    double st = tick_step(span, 8);
    std::vector<Tick> ts = ticks(t0_, t1_, st);
    while (widest(ts) + 12 > plot_w_ * st / span) {
      st = tick_step(st * 1.5, 1);
      ts = ticks(t0_, t1_, st);
    }
    const double base = y_sen_ + kSensorH;
    o_ += "<g id=\"time-axis\">\n";
    for (const auto& tick : ts) {
      const double x = tx(tick.value);
      o_ += fmt::format("<line x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{:.0f}\" y2=\"{:.0f}\" stroke=\"#444\"/>\n", x, x, base,
                        base + 5);
      o_ += fmt::format("<text class=\"tick\" x=\"{:.1f}\" y=\"{:.0f}\" text-anchor=\"middle\">{}</text>\n", x, base + 17,
                        tick.text);
    }
    o_ += fmt::format("<text class=\"axis-label\" x=\"{:.0f}\" y=\"{:.0f}\" text-anchor=\"middle\">time (ms)</text>\n",
                      left_ + plot_w_ / 2, base + 34);
    o_ += "</g>\n";
  }

  // The reference edge: where the homing found its reference. Its label reads
  // to the right of the line, or to the left where the plot ends.
  void reference_edge() {
    if (!edge_shown()) return;
    const double x = tx(*t_.edge_time_ms);
    const std::string label = fmt::format("reference edge {:.3f} {} at {} ms", t_.edge_position_mm,
                                          t_.unit(), *t_.edge_time_ms);
    const bool left_of_line = x + 4 + text_width(label, kFont) > left_ + plot_w_;
    o_ += "<g id=\"reference-edge\">\n";
    o_ += fmt::format("<line x1=\"{:.2f}\" x2=\"{:.2f}\" y1=\"{:.0f}\" y2=\"{:.0f}\" stroke=\"#d00000\" "
                      "stroke-width=\"1.5\" stroke-dasharray=\"5,3\"/>\n",
                      x, x, top_, y_sen_ + kSensorH);
    o_ += fmt::format("<text x=\"{:.2f}\" y=\"{:.0f}\" fill=\"#d00000\" text-anchor=\"{}\">{}</text>\n",
                      left_of_line ? x - 4 : x + 4, top_ + 12, left_of_line ? "end" : "start", label);
    o_ += "</g>\n";
  }

  // Legend items in rows as wide as the plots.
  void place_legend(double y) {
    std::vector<LegendItem> items;
    for (const auto& s : t_.samples)
      if (std::none_of(items.begin(), items.end(), [&](const auto& i) { return i.label == homing::phase_name(s.phase); }))
        items.push_back({std::string(homing::phase_name(s.phase)), phase_colour(s.phase)});
    if (edge_shown()) items.push_back({"reference edge", ""});
    double x = left_;
    for (auto& item : items) {
      const double w = 20 + text_width(item.label, kFont);
      if (x > left_ && x + w > left_ + plot_w_) {
        x = left_;
        y += kLegendRow;
      }
      item.x = x;
      item.y = y;
      x += w + 14;
    }
    legend_ = std::move(items);
    height_ = y + 12 + 20;
  }

  void legend() {
    o_ += "<g id=\"legend\">\n";
    for (const auto& item : legend_) {
      if (item.colour.empty())
        o_ += fmt::format("<line x1=\"{:.0f}\" x2=\"{:.0f}\" y1=\"{:.0f}\" y2=\"{:.0f}\" stroke=\"#d00000\" "
                          "stroke-dasharray=\"5,3\"/>\n<text x=\"{:.0f}\" y=\"{:.0f}\">{}</text>\n",
                          item.x, item.x + 16, item.y + 6, item.y + 6, item.x + 20, item.y + 10, item.label);
      else
        o_ += fmt::format("<rect x=\"{:.0f}\" y=\"{:.0f}\" width=\"12\" height=\"12\" fill=\"{}\" fill-opacity=\"0.6\" "
                          "stroke=\"#888\"/>\n<text class=\"legend-phase\" x=\"{:.0f}\" y=\"{:.0f}\">{}</text>\n",
                          item.x, item.y, item.colour, item.x + 20, item.y + 10, item.label);
    }
    o_ += "</g>\n";
  }

  const Trace& t_;
  double t0_ = 0, t1_ = 1;
  double p_lo_ = 0, p_hi_ = 1, v_lo_ = 0, v_hi_ = 1;
  std::vector<Tick> p_ticks_, v_ticks_;
  double left_ = kMinLeft, plot_w_ = 0, top_ = 0, y_vel_ = 0, y_sen_ = 0, height_ = 0;
  std::vector<std::string> title_, alarm_;
  std::vector<LegendItem> legend_;
  std::string o_;
};

}  // namespace

std::string trace_svg(const Trace& t, const std::string& alarm_text) { return Drawing(t, alarm_text).svg(); }

}  // namespace homingctl
