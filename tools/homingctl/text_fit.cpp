#include "text_fit.hpp"

#include <array>

namespace homingctl {

namespace {

// Advance widths of DejaVu Sans and DejaVu Sans Bold (hmtx) for printable
// ASCII (32..126), in em.
constexpr std::array<double, 95> kAscii = {
    0.318, 0.401, 0.460, 0.838, 0.636, 0.950, 0.780, 0.275, 0.390, 0.390, 0.500, 0.838, 0.318, 0.361, 0.318, 0.337,
    0.636, 0.636, 0.636, 0.636, 0.636, 0.636, 0.636, 0.636, 0.636, 0.636, 0.337, 0.337, 0.838, 0.838, 0.838, 0.531,
    1.000, 0.684, 0.686, 0.698, 0.770, 0.632, 0.575, 0.775, 0.752, 0.295, 0.295, 0.656, 0.557, 0.863, 0.748, 0.787,
    0.603, 0.787, 0.695, 0.635, 0.611, 0.732, 0.684, 0.989, 0.685, 0.611, 0.685, 0.390, 0.337, 0.390, 0.838, 0.500,
    0.500, 0.613, 0.635, 0.550, 0.635, 0.615, 0.352, 0.635, 0.634, 0.278, 0.278, 0.579, 0.278, 0.974, 0.634, 0.612,
    0.635, 0.635, 0.411, 0.521, 0.392, 0.634, 0.592, 0.818, 0.592, 0.592, 0.525, 0.636, 0.337, 0.636, 0.838};
constexpr std::array<double, 95> kAsciiBold = {
    0.348, 0.456, 0.521, 0.838, 0.696, 1.002, 0.872, 0.306, 0.457, 0.457, 0.523, 0.838, 0.380, 0.415, 0.380, 0.365,
    0.696, 0.696, 0.696, 0.696, 0.696, 0.696, 0.696, 0.696, 0.696, 0.696, 0.400, 0.400, 0.838, 0.838, 0.838, 0.580,
    1.000, 0.774, 0.762, 0.734, 0.830, 0.683, 0.683, 0.821, 0.837, 0.372, 0.372, 0.775, 0.637, 0.995, 0.837, 0.850,
    0.733, 0.850, 0.770, 0.720, 0.682, 0.812, 0.774, 1.103, 0.771, 0.724, 0.725, 0.457, 0.365, 0.457, 0.838, 0.500,
    0.500, 0.675, 0.716, 0.593, 0.716, 0.678, 0.435, 0.716, 0.712, 0.343, 0.343, 0.665, 0.343, 1.042, 0.712, 0.687,
    0.716, 0.716, 0.493, 0.595, 0.478, 0.712, 0.652, 0.924, 0.645, 0.652, 0.582, 0.712, 0.365, 0.712, 0.838};
constexpr double kOther = 1.0;  // a character outside ASCII (µ, ², …): as wide as the widest letter

}  // namespace

double text_width(std::string_view text, double font_px, bool bold) {
  const auto& widths = bold ? kAsciiBold : kAscii;
  double em = 0;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c >= 32 && c < 127) em += widths[c - 32];
    else if ((c & 0xC0) != 0x80) em += kOther;  // the first byte of a UTF-8 sequence counts once
  }
  return em * font_px;
}

std::vector<std::string> wrap_text(std::string_view text, double width, double font_px, bool bold) {
  std::vector<std::string> lines;
  std::string line;
  auto fits = [&](std::string_view s) { return text_width(s, font_px, bold) <= width; };
  auto add_word = [&](std::string_view word) {
    const std::string joined = line.empty() ? std::string(word) : line + " " + std::string(word);
    if (fits(joined)) {
      line = joined;
      return;
    }
    if (!line.empty()) lines.push_back(line);
    line.clear();
    for (std::size_t i = 0; i < word.size();) {  // a word wider than a line: broken where it must be
      std::size_t n = 1;
      while (i + n < word.size() && (static_cast<unsigned char>(word[i + n]) & 0xC0) == 0x80) ++n;
      const std::string longer = line + std::string(word.substr(i, n));
      if (!line.empty() && !fits(longer)) {
        lines.push_back(line);
        line.clear();
        continue;
      }
      line = longer;
      i += n;
    }
  };
  std::size_t at = 0;
  while (at <= text.size()) {
    const auto space = text.find(' ', at);
    const auto word = text.substr(at, space == std::string_view::npos ? std::string_view::npos : space - at);
    if (!word.empty()) add_word(word);
    if (space == std::string_view::npos) break;
    at = space + 1;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

}  // namespace homingctl
