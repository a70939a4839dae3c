// history: the module's history from its database file (history.hpp), the
// one front end for it (homing-settings points here).
#include <fmt/format.h>

#include "cli.hpp"
#include "history.hpp"

namespace homingctl {

namespace {

int history(const Context& ctx, const HistoryRequest& request) {
  auto h = read_history(ctx.db, request);
  if (!h) {
    fmt::print(stderr, "homingctl history: {}\n", h.error());
    return kFailed;
  }
  if (ctx.json) print_json(h->json); else fmt::print("{}", h->text);
  return kOk;
}

}  // namespace

void add_history_command(Commands& commands, Context& ctx) {
  auto o = std::make_shared<HistoryRequest>();
  auto* sub = commands.add("history", "recent homing runs and settings changes (reads the daemon's database "
                                      "file read-only: not served over Modbus)",
                           [o](Context& c) { return history(c, *o); });
  sub->add_option("--db", ctx.db, "the daemon's --db file")->capture_default_str();
  sub->add_option("-n,--runs", o->runs, "homing runs shown")->capture_default_str();
  sub->add_option("--changes", o->changes, "settings changes shown")->capture_default_str();
  sub->add_option("--corrections", o->corrections,
                  "home correction per axis (mean, spread, stddev) over this many runs (0 = not shown)")
      ->capture_default_str();
}

}  // namespace homingctl
