// homingctl trace --from/--to (a time window of the samples) and the drawing's
// labels: each fits the picture and none overlaps another, with the longest
// axis, phase and alarm names.
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <cmath>
#include <regex>
#include <sstream>

#include "text_fit.hpp"
#include "tools_helpers.hpp"
#include "trace.hpp"

using namespace tools_test;


namespace {

// A trace of axis C (rotary, "deg") through every phase, with wide values, the
// longest alarm name and the reference edge at the very end: the labels most
// likely not to fit.
homingctl::Trace widest_trace() {
  homingctl::Trace t;
  t.axis = 5;
  t.interval_ms = 0.5;
  std::uint32_t time = 0;
  for (const auto& info : homing::kPhaseInfo)
    for (int i = 0; i < 20; ++i, time += 7)
      t.samples.push_back({time, info.value, (time % 2 ? -1 : 1) * 99999.999, -12345.678 + time, i % 2 == 0});
  t.duration_ms = time;
  t.edge_time_ms = t.samples.back().time_ms;
  t.edge_position_mm = -99999.999;
  for (const auto& info : homing::kAlarmInfo)
    if (info.name.size() > homing::alarm_name(t.alarm).size()) t.alarm = info.value;
  return t;
}

struct Label {
  std::string text;
  double x0, x1, y0, y1;
};

std::string unescape(std::string s) {
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&amp;", "&"}}) {
    for (auto at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
  }
  return s;
}

// Every <text> of an SVG with the box it is drawn in (font size and weight,
// anchor, a -90° rotation), measured with the drawing's own font metrics.
std::vector<Label> labels_of(const std::string& svg) {
  std::vector<Label> out;
  const std::regex text_re("<text([^>]*)>([^<]*)</text>");
  auto attr = [](const std::string& attrs, const std::string& name) -> std::optional<std::string> {
    std::smatch m;
    if (std::regex_search(attrs, m, std::regex(" " + name + "=\"([^\"]*)\""))) return m[1].str();
    return std::nullopt;
  };
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), text_re); it != std::sregex_iterator(); ++it) {
    const std::string attrs = (*it)[1].str(), text = unescape((*it)[2].str());
    const double size = std::stod(attr(attrs, "font-size").value_or("11"));
    const bool bold = attr(attrs, "font-weight") == "bold";
    const double w = homingctl::text_width(text, size, bold);
    const std::string anchor = attr(attrs, "text-anchor").value_or("start");
    const double shift = anchor == "middle" ? w / 2 : anchor == "end" ? w : 0;
    const double x = std::stod(attr(attrs, "x").value()), y = std::stod(attr(attrs, "y").value());
    if (attr(attrs, "transform")) {  // rotate(-90 x y): the text runs upwards from y
      out.push_back({text, x - 0.8 * size, x + 0.25 * size, y - (w - shift), y + shift});
    } else {
      out.push_back({text, x - shift, x - shift + w, y - 0.8 * size, y + 0.25 * size});
    }
  }
  return out;
}

// Each label inside the picture and clear of every other one.
void check_labels_fit(const std::string& svg) {
  std::smatch m;
  REQUIRE(std::regex_search(svg, m, std::regex("<svg [^>]*width=\"([0-9.]+)\" height=\"([0-9.]+)\"")));
  const double width = std::stod(m[1].str()), height = std::stod(m[2].str());
  const auto labels = labels_of(svg);
  REQUIRE(labels.size() > 20);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const Label& a = labels[i];
    INFO("label '" << a.text << "' at " << a.x0 << ".." << a.x1 << " x " << a.y0 << ".." << a.y1);
    CHECK(a.x0 >= 0);
    CHECK(a.x1 <= width);
    CHECK(a.y0 >= 0);
    CHECK(a.y1 <= height);
    for (std::size_t j = i + 1; j < labels.size(); ++j) {
      const Label& b = labels[j];
      INFO("overlaps '" << b.text << "' at " << b.x0 << ".." << b.x1 << " x " << b.y0 << ".." << b.y1);
      CHECK((a.x1 <= b.x0 || b.x1 <= a.x0 || a.y1 <= b.y0 || b.y1 <= a.y0));
    }
  }
}

}  // namespace

TEST_CASE("every label of a trace drawing fits the picture and no two overlap, with the longest names") {
  const auto t = widest_trace();
  const std::string alarm =
      "C: the longest alarm text an HMI could show, repeated until it is far wider than the drawing: "
      "the commutator released the slave while the master was still travelling at its seek feedrate, check "
      "the wiring of the commutator output, its polarity, and the slave's drive enable; a path with no spaces "
      "/var/lib/homingd/a-very-long-file-name-without-any-space-that-must-still-be-broken-somewhere.toml";
  const std::string svg = homingctl::trace_svg(t, alarm);
  check_labels_fit(svg);
  // Every phase is in the legend, the alarm text is all there (over several lines), the edge is labelled.
  CHECK(count_of(svg, "class=\"legend-phase\"") == std::size(homing::kPhaseInfo));
  std::string alarm_shown;
  for (const auto& l : labels_of(svg))
    if (alarm.find(l.text) != std::string::npos && l.text.size() > 3) alarm_shown += l.text;
  CHECK(alarm_shown.size() + 40 > alarm.size());  // the words, less the spaces where it wrapped
  CHECK(svg.find("position (deg)") != std::string::npos);
  CHECK(svg.find("velocity (deg/s)") != std::string::npos);
  CHECK(svg.find("text-anchor=\"end\">reference edge -99999.999 deg") != std::string::npos);  // turned left at the end

  // Zoomed into half a millisecond of it: ticks fit and lie in the window.
  auto zoomed = homingctl::window_trace(t, 0.504, 0.5045);
  REQUIRE(zoomed);
  const std::string zsvg = homingctl::trace_svg(*zoomed, alarm);
  check_labels_fit(zsvg);
  const std::regex tick_re("<text class=\"tick\" x=\"[0-9.]+\" y=\"[0-9.]+\" text-anchor=\"middle\">([-0-9.]+)</text>");
  std::size_t time_ticks = 0;
  for (auto it = std::sregex_iterator(zsvg.begin(), zsvg.end(), tick_re); it != std::sregex_iterator(); ++it, ++time_ticks) {
    const double ms = std::stod((*it)[1].str());
    CHECK(ms >= 504.0 - 1e-9);
    CHECK(ms <= 504.5 + 1e-9);
  }
  CHECK(time_ticks >= 2);
  // The title says which part is shown (over as many lines as it needs).
  const auto title_start = zsvg.find("<g id=\"title\">"), title_end = zsvg.find("</g>", title_start);
  std::string title;
  for (const auto& l : labels_of(zsvg.substr(title_start, title_end - title_start))) title += (title.empty() ? "" : " ") + l.text;
  CHECK_THAT(title, Catch::Contains("shown 0.504 s to 0.5045 s"));
}

TEST_CASE("a trace window keeps the samples inside it and refuses a window that is negative, empty or past the end") {
  homingctl::Trace t;
  t.interval_ms = 10;
  for (std::uint32_t ms = 0; ms <= 1000; ms += 10) t.samples.push_back({ms, homing::Phase::seek, ms / 100.0, 1, false});
  t.duration_ms = 1000;

  auto w = homingctl::window_trace(t, 0.2, 0.3);
  REQUIRE(w);
  REQUIRE(w->samples.size() == 11);  // 200 .. 300 ms, both ends included
  CHECK(w->samples.front().time_ms == 200);
  CHECK(w->samples.back().time_ms == 300);
  CHECK(homingctl::trace_csv(*w).find("\n190,") == std::string::npos);
  CHECK(homingctl::trace_json(*w)["window"]["from_s"] == Approx(0.2));
  CHECK(homingctl::trace_json(*w)["samples"].size() == 11);

  w = homingctl::window_trace(t, 0.95, std::nullopt);  // to the end
  REQUIRE(w);
  CHECK(w->samples.size() == 6);
  CHECK(w->window->to_ms == Approx(1000));
  w = homingctl::window_trace(t, std::nullopt, 0.05);  // from the start
  REQUIRE(w);
  CHECK(w->samples.size() == 6);
  CHECK(homingctl::trace_json(t)["window"].is_null());

  auto refused = [&](std::optional<double> from, std::optional<double> to) {
    auto r = homingctl::window_trace(t, from, to);
    REQUIRE_FALSE(r);
    return r.error();
  };
  CHECK_THAT(refused(-0.1, std::nullopt), Catch::Contains("--from -0.1"));
  CHECK_THAT(refused(std::nullopt, -1.0), Catch::Contains("--to -1"));
  CHECK_THAT(refused(0.3, 0.2), Catch::Contains("--from 0.3 is not before --to 0.2"));
  CHECK_THAT(refused(0.3, 0.3), Catch::Contains("--from 0.3 is not before --to 0.3"));
  CHECK_THAT(refused(std::nan(""), std::nullopt), Catch::Contains("--from nan"));
  CHECK_THAT(refused(2.0, std::nullopt), Catch::Contains("--from 2: the trace of X ends at 1.000 s"));
  CHECK_THAT(refused(0.201, 0.205), Catch::Contains("no sample of X between --from 0.201 and --to 0.205"));
}

TEST_CASE("homingctl trace --from --to zooms into part of a real cycle and refuses a bad window") {
  Daemon d;
  REQUIRE(ctl(d, {"home"}).code() == 0);
  const auto whole = json_of(ctl(d, {"trace", "x", "--json"}));
  const double duration_s = whole["duration_ms"].get<double>() / 1000.0;
  REQUIRE(duration_s > 0.1);
  const double from = duration_s / 4, to = duration_s / 2;
  const std::string from_text = fmt::format("{:.3f}", from), to_text = fmt::format("{:.3f}", to);

  auto r = ctl(d, {"trace", "x", "--csv", "-", "--from", from_text, "--to", to_text});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
  }
  std::size_t rows = 0;
  std::istringstream lines(r.out);
  std::string line;
  std::getline(lines, line);
  CHECK(line == "time_ms,phase,position_mm,velocity_mm_per_s,sensor");
  while (std::getline(lines, line)) {
    const double ms = std::stod(line.substr(0, line.find(',')));
    CHECK(ms >= std::stod(from_text) * 1000 - 1e-6);
    CHECK(ms <= std::stod(to_text) * 1000 + 1e-6);
    ++rows;
  }
  CHECK(rows > 0);
  CHECK(rows < whole["samples"].size());

  const auto j = json_of(ctl(d, {"trace", "x", "--json", "--from", from_text, "--to", to_text}));
  CHECK(j["window"]["from_s"].get<double>() == Approx(std::stod(from_text)));
  CHECK(j["samples"].size() == rows);
  r = ctl(d, {"trace", "x", "--from", from_text, "--to", to_text});
  CHECK(r.code() == 0);
  CHECK(r.out.find(fmt::format("from {:g} s to {:g} s of a", std::stod(from_text), std::stod(to_text))) !=
        std::string::npos);

  for (const auto& [args, says] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--from=-1"}, "--from -1"},
           {{"--from", "2", "--to", "1"}, "--from 2 is not before --to 1"},
           {{"--to", "0"}, "--from 0 is not before --to 0"},
           {{"--from", "100000"}, "--from 100000: the trace of X ends at"}}) {
    std::vector<std::string> argv{"trace", "x"};
    argv.insert(argv.end(), args.begin(), args.end());
    r = ctl(d, argv);
    SHOW(r);
    CHECK(r.code() == 2);
    CHECK(r.err.find(says) != std::string::npos);
  }
}
