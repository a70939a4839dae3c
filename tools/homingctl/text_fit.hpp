#pragma once
// How wide a label is drawn, so the trace drawing can make every label fit the
// width it has (wrap a sentence, widen a margin, space ticks, start a new
// legend row) instead of letting it run off the page or over another label.
// Widths are those of DejaVu Sans, the widest of the usual sans-serif fonts
// (a viewer with Arial or Helvetica draws narrower, never wider).
#include <string>
#include <string_view>
#include <vector>

namespace homingctl {

// Width in pixels of `text` (UTF-8) at `font_px`; bold is drawn wider.
double text_width(std::string_view text, double font_px, bool bold = false);

// `text` broken at spaces into lines no wider than `width` (a word longer than
// a line is broken inside, so no line is ever wider).
std::vector<std::string> wrap_text(std::string_view text, double width, double font_px, bool bold = false);

}  // namespace homingctl
