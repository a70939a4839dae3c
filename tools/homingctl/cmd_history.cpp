// history: the module's history from its database file (history.hpp), the
// one front end for it (homing-settings points here).
#include <fmt/format.h>

#include "actions.hpp"
#include "cli.hpp"
#include "history.hpp"
#include "settings_io.hpp"

namespace homingctl {

namespace {

struct HistoryOptions {
  HistoryRequest request;
  std::string trend_axis;  // --trend: one axis's health figures instead of the runs
  std::string svg_file;    // with --trend: drawn to this file
};

// --trend AXIS: the axis's health figures over its last -n cycles, as a table, JSON or an SVG.
int trend(const Context& ctx, const HistoryOptions& o) {
  const int index = axis_index(o.trend_axis);
  if (index < 0) throw Usage(fmt::format("history: --trend '{}' is not an axis (x, y, z, a, b, c)", o.trend_axis));
  auto t = read_health_trend(ctx.db, static_cast<std::size_t>(index), o.request.runs);
  if (!t) {
    fmt::print(stderr, "homingctl history: {}\n", t.error());
    return kFailed;
  }
  if (!o.svg_file.empty()) {
    if (auto w = write_file_atomically(o.svg_file, trend_svg(*t)); !w) {
      fmt::print(stderr, "homingctl history: {}\n", w.error());
      return kFailed;
    }
    if (!ctx.json) fmt::print("{}: {} cycles drawn to {}\n", homing::kAxisUpper[t->axis], t->cycles.size(), o.svg_file);
    return kOk;
  }
  if (ctx.json) print_json(trend_json(*t)); else fmt::print("{}", trend_table(*t));
  return kOk;
}

int history(const Context& ctx, const HistoryOptions& o) {
  if (!o.trend_axis.empty()) return trend(ctx, o);
  if (!o.svg_file.empty()) throw Usage("history: --svg draws the health trend of one axis: give --trend AXIS too");
  auto h = read_history(ctx.db, o.request);
  if (!h) {
    fmt::print(stderr, "homingctl history: {}\n", h.error());
    return kFailed;
  }
  if (ctx.json) print_json(h->json); else fmt::print("{}", h->text);
  return kOk;
}

}  // namespace

void add_history_command(Commands& commands, Context& ctx) {
  auto o = std::make_shared<HistoryOptions>();
  auto* sub = commands.add("history", "recent homing runs and settings changes, or one axis's health trend (reads "
                                      "the daemon's database file read-only: not served over Modbus)",
                           [o](Context& c) { return history(c, *o); });
  sub->add_option("--db", ctx.db, "the daemon's --db file")->capture_default_str();
  sub->add_option("-n,--runs", o->request.runs, "homing runs shown (with --trend: the axis's last cycles)")
      ->capture_default_str();
  sub->add_option("--changes", o->request.changes, "settings changes shown")->capture_default_str();
  sub->add_option("--corrections", o->request.corrections,
                  "home correction per axis (mean, spread, stddev) over this many runs (0 = not shown)")
      ->capture_default_str();
  sub->add_option("--trend", o->trend_axis,
                  "one axis's switch health figures and gantry skew cycle by cycle (docs/health.md)");
  sub->add_option("--svg", o->svg_file, "with --trend: draw the figures against the runs to this SVG file");
}

}  // namespace homingctl
