#include "svg_parts.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "text_fit.hpp"

namespace homingctl {

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

double tick_step(double span, int want) {
  if (span <= 0) return 1;
  const double raw = span / want;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * mag) return m * mag;
  return 10 * mag;
}

std::string tick_text(double v, double step) {
  const int decimals = step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
  if (std::abs(v) < step * 1e-6) v = 0;
  return fmt::format("{:.{}f}", v, decimals);
}

std::vector<Tick> ticks(double lo, double hi, double step) {
  std::vector<Tick> out;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step) out.push_back({v, tick_text(v, step)});
  return out;
}

double widest(const std::vector<Tick>& ts, double font_px) {
  double w = 0;
  for (const auto& t : ts) w = std::max(w, text_width(t.text, font_px));
  return w;
}

}  // namespace homingctl
