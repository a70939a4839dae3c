// One axis's health figures over its cycles in the history, drawn as an SVG:
// a plot per figure the cycles measured (latch spread and sigma, hysteresis,
// seek-latch difference, chatter, index distance, gantry skew), each cycle a
// point against its run, so a figure that grows shows as a line that climbs.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "history.hpp"
#include "homing/axes.hpp"
#include "svg_parts.hpp"
#include "text_fit.hpp"

namespace homingctl {

namespace {

constexpr double kWidth = 960, kMargin = 20, kMinLeft = 80;
constexpr double kFont = 11, kTitleFont = 15, kTitleLine = 19;
constexpr double kPlotH = 110, kGap = 26;
constexpr double kAxisLabelX = 12;  // the rotated axis labels' baseline

using persistence::AxisHealth;

// One plotted figure: its value in a cycle, or none where that cycle did not measure it.
struct Figure {
  std::string_view id;     // data-figure
  std::string_view label;  // "hysteresis"
  bool length;             // in the axis's unit, else a count
  std::string_view colour;
  std::optional<double> (*value)(const AxisHealth&);
};

constexpr Figure kFigures[] = {
    {"latch_spread", "latch spread", true, "#1f4e9c",
     [](const AxisHealth& h) { return h.latch_passes >= 2 ? std::optional(h.latch_spread_mm) : std::nullopt; }},
    {"latch_sigma", "latch sigma", true, "#4a7fd0",
     [](const AxisHealth& h) { return h.latch_passes >= 2 ? std::optional(h.latch_sigma_mm) : std::nullopt; }},
    {"hysteresis", "hysteresis", true, "#b03030",
     [](const AxisHealth& h) { return h.hysteresis_mm > 0 ? std::optional(h.hysteresis_mm) : std::nullopt; }},
    {"seek_latch_difference", "seek-latch difference", true, "#2a8c3a",
     [](const AxisHealth& h) {
       return h.latch_passes >= 1 && h.seek_latch_mm != 0 ? std::optional(h.seek_latch_mm) : std::nullopt;
     }},
    {"chatter_edges", "chatter", false, "#8c5a2a",
     [](const AxisHealth& h) { return std::optional(static_cast<double>(h.chatter_edges)); }},
    {"index_distance", "index distance", true, "#7a3a9c",
     [](const AxisHealth& h) { return h.index_distance_mm > 0 ? std::optional(h.index_distance_mm) : std::nullopt; }},
    {"gantry_skew", "gantry skew", true, "#d07000", [](const AxisHealth& h) { return h.gantry_skew_mm; }},
};

struct Panel {
  const Figure* figure = nullptr;
  double lo = 0, hi = 0;
  std::vector<Tick> ticks;
};

class Drawing {
 public:
  explicit Drawing(const HealthTrend& t) : t_(t) {
    for (const Figure& f : kFigures) {
      std::optional<double> lo, hi;
      for (const auto& r : t.cycles)
        if (const auto v = f.value(r.health)) {
          lo = lo ? std::min(*lo, *v) : *v;
          hi = hi ? std::max(*hi, *v) : *v;
        }
      if (!lo) continue;  // no cycle measured it
      Panel p{&f, *lo, *hi, {}};
      if (p.hi - p.lo < 1e-9) {  // a flat line sits in the middle of its plot
        const double half = std::max(std::abs(p.lo) * 0.5, f.length ? 0.001 : 1.0);
        p.lo -= half;
        p.hi += half;
      }
      const double pad = (p.hi - p.lo) * 0.08;
      p.lo -= pad;
      p.hi += pad;
      p.ticks = ticks(p.lo, p.hi, tick_step(p.hi - p.lo, 4));
      panels_.push_back(std::move(p));
    }
    double ticks_w = 0;
    for (const auto& p : panels_) ticks_w = std::max(ticks_w, widest(p.ticks, kFont));
    left_ = std::max(kMinLeft, std::ceil(ticks_w + 6 + kAxisLabelX + 0.2 * kFont + 6));
    plot_w_ = kWidth - left_ - kMargin;
    title_ = wrap_text(title_text(), kWidth - 2 * kMargin, kTitleFont, true);
    top_ = 22 + kTitleLine * static_cast<double>(title_.size() - 1) + 26;
    const double plots = static_cast<double>(panels_.size()) * (kPlotH + kGap);
    height_ = top_ + plots + 50;
  }

  std::string svg() {
    o_ += fmt::format("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" viewBox=\"0 0 {:.0f} "
                      "{:.0f}\" font-family=\"DejaVu Sans, sans-serif\" font-size=\"{:g}\">\n",
                      kWidth, height_, kWidth, height_, kFont);
    o_ += fmt::format("<rect width=\"{:.0f}\" height=\"{:.0f}\" fill=\"white\"/>\n", kWidth, height_);
    o_ += "<g id=\"title\">\n";
    for (std::size_t i = 0; i < title_.size(); ++i)
      o_ += fmt::format("<text x=\"{:.0f}\" y=\"{:.0f}\" font-size=\"{:g}\" font-weight=\"bold\">{}</text>\n", kMargin,
                        22 + kTitleLine * static_cast<double>(i), kTitleFont, xml_escape(title_[i]));
    o_ += "</g>\n";
    for (std::size_t i = 0; i < panels_.size(); ++i)
      plot(panels_[i], top_ + static_cast<double>(i) * (kPlotH + kGap));
    run_axis(top_ + static_cast<double>(panels_.size()) * (kPlotH + kGap) - kGap);
    o_ += "</svg>\n";
    return std::move(o_);
  }

 private:
  std::string title_text() const {
    const char x = homing::kAxisUpper[t_.axis];
    if (t_.cycles.empty()) return fmt::format("Health trend, axis {}: no cycle with figures in the history", x);
    return fmt::format("Health trend, axis {}: {} cycles, runs #{} to #{}", x, t_.cycles.size(),
                       t_.cycles.front().run_id, t_.cycles.back().run_id);
  }

  // Cycle i of n, evenly spaced (the runs of other axes leave gaps in the numbers).
  double cx(std::size_t i) const {
    const std::size_t n = t_.cycles.size();
    return n < 2 ? left_ + plot_w_ / 2 : left_ + plot_w_ * static_cast<double>(i) / static_cast<double>(n - 1);
  }

  void plot(const Panel& p, double y0) {
    const Figure& f = *p.figure;
    auto ty = [&](double v) { return y0 + kPlotH - kPlotH * (v - p.lo) / (p.hi - p.lo); };
    const std::string label = f.length ? fmt::format("{} ({})", f.label, t_.unit) : fmt::format("{} (edges)", f.label);
    o_ += fmt::format("<g id=\"{}\">\n", f.id);
    o_ += fmt::format("<rect class=\"frame\" x=\"{:.0f}\" y=\"{:.0f}\" width=\"{:.0f}\" height=\"{:.0f}\" fill=\"none\" "
                      "stroke=\"#444\"/>\n",
                      left_, y0, plot_w_, kPlotH);
    o_ += fmt::format("<text class=\"axis-label\" x=\"{:g}\" y=\"{:.0f}\" transform=\"rotate(-90 {:g} {:.0f})\" "
                      "text-anchor=\"middle\">{}</text>\n",
                      kAxisLabelX, y0 + kPlotH / 2, kAxisLabelX, y0 + kPlotH / 2, xml_escape(label));
    for (const auto& tick : p.ticks) {
      o_ += fmt::format("<line class=\"grid\" x1=\"{:.0f}\" x2=\"{:.0f}\" y1=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>\n",
                        left_, left_ + plot_w_, ty(tick.value), ty(tick.value));
      o_ += fmt::format("<text class=\"tick\" x=\"{:.0f}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n", left_ - 6,
                        ty(tick.value) + 4, tick.text);
    }
    std::string line, points;
    for (std::size_t i = 0; i < t_.cycles.size(); ++i) {
      const auto& r = t_.cycles[i];
      const auto v = f.value(r.health);
      if (!v) continue;
      line += fmt::format("{:.2f},{:.2f} ", cx(i), ty(*v));
      points += fmt::format("<circle class=\"point\" data-figure=\"{}\" data-run=\"{}\" data-value=\"{:.6g}\" "
                            "cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"2.5\" fill=\"{}\"><title>run #{}: {:.4g} {}</title></circle>\n",
                            f.id, r.run_id, *v, cx(i), ty(*v), f.colour, r.run_id, *v,
                            f.length ? t_.unit : std::string("edges"));
    }
    o_ += fmt::format("<polyline class=\"trend\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" points=\"{}\"/>\n",
                      f.colour, line);
    o_ += points;
    o_ += "</g>\n";
  }

  // The runs under the last plot, labelled as far apart as their numbers need.
  void run_axis(double base) {
    o_ += "<g id=\"run-axis\">\n";
    const std::size_t n = t_.cycles.size();
    if (n > 0) {
      const double label_w = text_width(fmt::format("#{}", t_.cycles.back().run_id), kFont) + 12;
      const double spacing = n < 2 ? plot_w_ : plot_w_ / static_cast<double>(n - 1);
      const auto every = static_cast<std::size_t>(std::max(1.0, std::ceil(label_w / spacing)));
      for (std::size_t i = 0; i < n; i += every) {
        o_ += fmt::format("<line x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{:.0f}\" y2=\"{:.0f}\" stroke=\"#444\"/>\n", cx(i),
                          cx(i), base, base + 5);
        o_ += fmt::format("<text class=\"tick\" x=\"{:.1f}\" y=\"{:.0f}\" text-anchor=\"middle\">#{}</text>\n", cx(i),
                          base + 17, t_.cycles[i].run_id);
      }
    }
    o_ += fmt::format("<text class=\"axis-label\" x=\"{:.0f}\" y=\"{:.0f}\" text-anchor=\"middle\">homing run</text>\n",
                      left_ + plot_w_ / 2, base + 34);
    o_ += "</g>\n";
  }

  const HealthTrend& t_;
  std::vector<Panel> panels_;
  std::vector<std::string> title_;
  double left_ = kMinLeft, plot_w_ = 0, top_ = 0, height_ = 0;
  std::string o_;
};

}  // namespace

std::string trend_svg(const HealthTrend& t) { return Drawing(t).svg(); }

}  // namespace homingctl
