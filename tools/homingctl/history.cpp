#include "history.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include "homing/alarms.hpp"
#include "homing/axes.hpp"
#include "homing/gantry.hpp"
#include "persistence/settings_store.hpp"
#include "persistence/time_text.hpp"
#include "registers/defaults.hpp"
#include "registers/lookup.hpp"
#include "values.hpp"

namespace homingctl {

namespace {

std::string local_time(std::int64_t ms) { return persistence::time_text(ms, persistence::TimeZone::local); }

std::string shown(const std::string& name, std::int64_t raw, const registers::AxisKinds& kinds) {
  const registers::Register* r = registers::find_register(name);
  return r ? value_text(*r, raw, kinds) : std::to_string(raw);
}

// "  X Y excluded: not homed before the cycle": the axes of a run whose
// correction is not in the statistics, by reason.
std::string exclusions(const persistence::HomingRun& r) {
  std::string out;
  for (auto reason : {persistence::Excluded::not_homed_before, persistence::Excluded::cycle_failed}) {
    std::string axes;
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (r.axis[a].present && r.axis[a].excluded == reason) axes += fmt::format("{} ", homing::kAxisUpper[a]);
    if (!axes.empty()) out += fmt::format("  {}excluded: {}", axes, persistence::excluded_text(reason));
  }
  return out;
}

void add_runs(HistoryReport& out, const std::vector<persistence::HomingRun>& runs) {
  out.json["runs"] = nlohmann::json::array();
  out.text += fmt::format("homing runs (newest first, {} shown):\n", runs.size());
  for (const auto& r : runs) {
    std::string axes;
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (r.axes & (1u << a)) axes += homing::kAxisUpper[a];
    const auto code = static_cast<homing::AlarmCode>(r.result);
    std::string result = r.result == 0 ? "ok" : std::string(homing::alarm_name(code));
    if (r.result != 0 && r.alarm_axis >= 0 && r.alarm_axis < 6)
      result += fmt::format(" on {}", homing::kAxisUpper[static_cast<std::size_t>(r.alarm_axis)]);
    std::string corr;
    nlohmann::json jaxes = nlohmann::json::object();
    for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
      const auto& x = r.axis[a];
      if (!x.present) continue;
      corr += x.correction_mm ? fmt::format("  {} {:+.4f}", homing::kAxisUpper[a], *x.correction_mm) : "";
      jaxes[std::string(homing::kAxisLetters[a])] = {
          {"correction", x.correction_mm ? nlohmann::json(*x.correction_mm) : nlohmann::json(nullptr)},
          {"duration_ms", x.duration_ms},
          {"excluded", x.excluded == persistence::Excluded::no
                           ? nlohmann::json(nullptr)
                           : nlohmann::json(std::string(persistence::excluded_text(x.excluded)))}};
    }
    out.text += fmt::format("  #{:<5} {}  {:7.2f} s  axes {:<6} {}{}{}\n", r.id, local_time(r.start_ms),
                            (r.end_ms - r.start_ms) / 1000.0, axes, result, corr, exclusions(r));
    out.json["runs"].push_back({{"id", r.id}, {"start_ms", r.start_ms}, {"end_ms", r.end_ms}, {"result", result},
                                {"alarm_code", r.result}, {"axes", jaxes}});
  }
}

// Values in the units of the axes' kinds as the database holds them now.
void add_changes(HistoryReport& out, const std::vector<persistence::AuditEntry>& changes,
                 const registers::AxisKinds& kinds) {
  out.json["changes"] = nlohmann::json::array();
  out.text += fmt::format("settings changes (newest first, {} shown):\n", changes.size());
  for (const auto& c : changes) {
    out.text += fmt::format("  {}  {:<6} {:<22} {:<32} {} -> {}\n", local_time(c.time_ms), c.transport, c.client, c.name,
                            shown(c.name, c.old_value, kinds), shown(c.name, c.new_value, kinds));
    out.json["changes"].push_back({{"time_ms", c.time_ms}, {"transport", c.transport}, {"client", c.client},
                                   {"name", c.name}, {"old", c.old_value}, {"new", c.new_value}});
  }
}

// Mean, spread and standard deviation of each axis's home correction over
// its last n runs: how repeatable the reference edge is.
std::expected<void, std::string> add_corrections(HistoryReport& out, const persistence::SettingsStore& store,
                                                 std::size_t n) {
  out.json["corrections"] = nlohmann::json::array();
  out.text += fmt::format("home corrections per axis (last {} runs):\n", n);
  out.text += "  axis  runs   mean        spread      stddev\n";
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    auto s = store.correction_summary(a, n);
    if (!s) return std::unexpected(s.error().message);
    if (s->count == 0) continue;
    out.text += fmt::format("  {:<5} {:<6} {:+.4f}    {:.4f}      {:.4f}\n", homing::kAxisUpper[a], s->count, s->mean,
                            s->spread, s->stddev);
    out.json["corrections"].push_back({{"axis", homing::kAxisLetters[a]}, {"runs", s->count}, {"mean", s->mean},
                                       {"spread", s->spread}, {"stddev", s->stddev}, {"min", s->min},
                                       {"max", s->max}});
  }
  // Which of the newest n runs are left out, and why: a correction is
  // counted only when the axis was homed before its cycle started.
  auto runs = store.recent_runs(n);
  if (!runs) return std::unexpected(runs.error().message);
  out.json["excluded"] = nlohmann::json::array();
  for (const auto& r : *runs) {
    const std::string why = exclusions(r);
    if (why.empty()) continue;
    out.text += fmt::format("  run #{}:{}\n", r.id, why);
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (r.axis[a].present && r.axis[a].excluded != persistence::Excluded::no)
        out.json["excluded"].push_back({{"run", r.id},
                                        {"axis", homing::kAxisLetters[a]},
                                        {"reason", std::string(persistence::excluded_text(r.axis[a].excluded))}});
  }
  return {};
}

// The daemon's database, read-only.
std::expected<persistence::SettingsStore, std::string> open_history(const std::string& db) {
  struct stat st{};
  if (::stat(db.c_str(), &st) != 0)
    return std::unexpected(fmt::format("{}: no such database (give the daemon's --db file with --db)", db));
  auto logger = spdlog::default_logger();
  logger->set_level(spdlog::level::warn);
  persistence::OpenReport report;
  persistence::StoreOptions options;
  options.read_only = true;
  auto store = persistence::SettingsStore::open(db, {}, report, options);
  if (!store) return std::unexpected(fmt::format("{}: {}", db, store.error().message));
  return std::move(*store);
}

}  // namespace

std::expected<HistoryReport, std::string> read_history(const std::string& db, const HistoryRequest& request) {
  auto store = open_history(db);
  if (!store) return std::unexpected(store.error());
  auto runs = store->recent_runs(request.runs);
  if (!runs) return std::unexpected(runs.error().message);
  auto changes = store->recent_changes(request.changes);
  if (!changes) return std::unexpected(changes.error().message);

  HistoryReport out;
  add_runs(out, *runs);
  add_changes(out, *changes, registers::kinds_of(registers::settings_from_raw(store->load()).settings));
  if (request.corrections > 0)
    if (auto c = add_corrections(out, *store, request.corrections); !c) return std::unexpected(c.error());
  return out;
}

std::expected<HealthTrend, std::string> read_health_trend(const std::string& db, std::size_t axis,
                                                          std::size_t cycles) {
  auto store = open_history(db);
  if (!store) return std::unexpected(store.error());
  auto records = store->health_history(axis, cycles);
  if (!records) return std::unexpected(records.error().message);
  HealthTrend t;
  t.axis = axis;
  t.unit = std::string(homing::axis_unit(registers::settings_from_raw(store->load()).settings, axis));
  t.cycles = std::move(*records);
  return t;
}

std::string trend_table(const HealthTrend& t) {
  std::string out = fmt::format("health figures of {} (oldest first, {} cycles, lengths in {}):\n",
                                homing::kAxisUpper[t.axis], t.cycles.size(), t.unit);
  out += fmt::format("  {:<6} {:<19} {:>6} {:>9} {:>9} {:>10} {:>10} {:>7} {:>9} {:>9}\n", "run", "time", "passes",
                     "spread", "sigma", "hysteresis", "seek-latch", "chatter", "index", "skew");
  for (const auto& r : t.cycles) {
    const auto& h = r.health;
    out += fmt::format("  #{:<5} {:<19} {:>6} {:>9.4f} {:>9.4f} {:>10.4f} {:>10.4f} {:>7} {:>9.4f} {:>9}{}\n", r.run_id,
                       local_time(r.start_ms), h.latch_passes, h.latch_spread_mm, h.latch_sigma_mm, h.hysteresis_mm,
                       h.seek_latch_mm, h.chatter_edges, h.index_distance_mm,
                       h.gantry_skew_mm ? fmt::format("{:.4f}", *h.gantry_skew_mm) : "-",
                       h.index_near_edge ? "  index near the switch edge" : "");
  }
  return out;
}

nlohmann::json trend_json(const HealthTrend& t) {
  nlohmann::json j = {{"axis", homing::kAxisLetters[t.axis]}, {"unit", t.unit}, {"cycles", nlohmann::json::array()}};
  for (const auto& r : t.cycles) {
    const auto& h = r.health;
    j["cycles"].push_back({{"run", r.run_id},
                           {"start_ms", r.start_ms},
                           {"latch_passes", h.latch_passes},
                           {"latch_spread", h.latch_spread_mm},
                           {"latch_sigma", h.latch_sigma_mm},
                           {"hysteresis", h.hysteresis_mm},
                           {"seek_latch_difference", h.seek_latch_mm},
                           {"chatter_edges", h.chatter_edges},
                           {"index_distance", h.index_distance_mm},
                           {"index_near_edge", h.index_near_edge},
                           {"gantry_skew", h.gantry_skew_mm ? nlohmann::json(*h.gantry_skew_mm) : nlohmann::json(nullptr)}});
  }
  return j;
}

}  // namespace homingctl
