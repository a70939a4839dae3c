// homing-settings: reads the module's settings database from the command line.
//   homing-settings --db /var/lib/homing/settings.db show
//   homing-settings --db ... audit -n 50
//   homing-settings --db ... history -n 20
//   homing-settings --db ... corrections -n 20
//   homing-settings --db ... export machine-7.toml
//   homing-settings --db ... check
// Opens the database read-only (safe while the module runs). Import is done by
// the module itself, which validates it like Modbus writes.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "persistence/settings_store.hpp"
#include "persistence/time_text.hpp"

namespace {

std::string local_time(std::int64_t ms) {
  return fmt::format("{}.{:03}", persistence::time_text(ms, persistence::TimeZone::local), ms % 1000);
}

constexpr const char* kAxis[] = {"X", "Y", "Z", "A", "B", "C"};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Read the homing module's settings database"};
  std::string db_path = "settings.db";
  std::size_t n = 20;
  std::string out_file;
  app.add_option("--db", db_path, "settings database file")->capture_default_str();
  auto* show = app.add_subcommand("show", "all settings (raw register values)");
  auto* audit = app.add_subcommand("audit", "recent settings changes, newest first");
  audit->add_option("-n", n, "rows")->capture_default_str();
  auto* history = app.add_subcommand("history", "recent homing runs, newest first");
  history->add_option("-n", n, "rows")->capture_default_str();
  auto* corr = app.add_subcommand("corrections", "home correction per axis over the last runs");
  corr->add_option("-n", n, "runs per axis")->capture_default_str();
  auto* exp = app.add_subcommand("export", "write all settings to a TOML file");
  exp->add_option("file", out_file, "output file")->required();
  auto* check = app.add_subcommand("check", "integrity check");
  app.require_subcommand(1);
  CLI11_PARSE(app, argc, argv);

  spdlog::set_level(spdlog::level::warn);
  persistence::OpenReport report;
  persistence::StoreOptions options;
  options.read_only = true;
  auto store = persistence::SettingsStore::open(db_path, {}, report, options);
  if (!store) {
    fmt::print(stderr, "error: {}\n", store.error().message);
    return 2;
  }
  auto fail = [](const persistence::Error& e) {
    fmt::print(stderr, "error: {}\n", e.message);
    return 1;
  };

  if (*show) {
    if (store->settings_lost()) fmt::print("# SETTINGS LOST: running on defaults, not yet acknowledged\n");
    for (const auto& [name, value] : store->load()) fmt::print("{} = {}\n", name, value);
  } else if (*audit) {
    auto rows = store->recent_changes(n);
    if (!rows) return fail(rows.error());
    for (const auto& r : *rows)
      fmt::print("{}  {:<6} {:<22} {:<32} {} -> {}\n", local_time(r.time_ms), r.transport, r.client, r.name,
                 r.old_value, r.new_value);
  } else if (*history) {
    auto runs = store->recent_runs(n);
    if (!runs) return fail(runs.error());
    for (const auto& r : *runs) {
      std::string axes;
      for (std::size_t a = 0; a < persistence::kHistoryAxes; ++a)
        if (r.axes & (1u << a)) axes += kAxis[a];
      fmt::print("#{} {}  {:.3f} s  axes {:<6} {}", r.id, local_time(r.start_ms), (r.end_ms - r.start_ms) / 1000.0,
                 axes, r.result == 0 ? std::string("ok") : fmt::format("alarm {}", r.result));
      if (r.result != 0 && r.alarm_axis >= 0 && r.alarm_axis < 6) fmt::print(" on {}", kAxis[r.alarm_axis]);
      for (std::size_t a = 0; a < persistence::kHistoryAxes; ++a) {
        const auto& x = r.axis[a];
        if (!x.present) continue;
        if (x.correction_mm)
          fmt::print("  {}: {:+.4f} ({} ms)", kAxis[a], *x.correction_mm, x.duration_ms);
        else
          fmt::print("  {}: - ({} ms)", kAxis[a], x.duration_ms);
      }
      fmt::print("\n");
    }
  } else if (*corr) {
    fmt::print("axis  runs   mean        spread      stddev\n");
    for (std::size_t a = 0; a < persistence::kHistoryAxes; ++a) {
      auto s = store->correction_summary(a, n);
      if (!s) return fail(s.error());
      if (s->count == 0) continue;
      fmt::print("{:<5} {:<6} {:+.4f}    {:.4f}      {:.4f}\n", kAxis[a], s->count, s->mean, s->spread, s->stddev);
    }
  } else if (*exp) {
    if (auto s = store->export_file(out_file); !s) return fail(s.error());
    fmt::print("exported {} settings to {}\n", store->load().size(), out_file);
  } else if (*check) {
    if (auto s = store->check_integrity(); !s) return fail(s.error());
    fmt::print("{}: ok (schema v{})\n", db_path, report.schema_version_found);
  }
  return 0;
}
