#pragma once
// What the SVG drawings (trace_svg.cpp, trend_svg.cpp) share: text made safe
// for XML, and round ticks on a value axis with as many decimals as their step needs.
#include <string>
#include <string_view>
#include <vector>

namespace homingctl {

std::string xml_escape(std::string_view s);

// Round tick step (1, 2 or 5 times a power of ten) for about `want` ticks over a span.
double tick_step(double span, int want);
// A tick value with as many decimals as its step needs ("0.05", "1200", never "-0").
std::string tick_text(double v, double step);

struct Tick {
  double value = 0;
  std::string text;
};
// The ticks from lo to hi, every step.
std::vector<Tick> ticks(double lo, double hi, double step);
// The widest tick label at `font_px`.
double widest(const std::vector<Tick>& ts, double font_px);

}  // namespace homingctl
