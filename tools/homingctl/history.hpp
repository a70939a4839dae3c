#pragma once
// The one reader of the module's history: recent homing runs, settings
// changes and the home corrections per axis, from the daemon's SQLite file
// opened read-only (the daemon does not serve its history over Modbus;
// SQLite's WAL lets this reader run next to the daemon). `homingctl history`
// is its front end; with --trend it shows one axis's health figures cycle by
// cycle (a table, JSON, or an SVG drawn by trend_svg.cpp).
#include <cstddef>
#include <expected>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "persistence/settings_store.hpp"

namespace homingctl {

struct HistoryRequest {
  std::size_t runs = 20;         // newest homing runs shown
  std::size_t changes = 20;      // newest settings changes shown
  std::size_t corrections = 0;   // runs per axis in the correction summary (0: no summary)
};

struct HistoryReport {
  std::string text;
  nlohmann::json json;
};

std::expected<HistoryReport, std::string> read_history(const std::string& db, const HistoryRequest& request);

// One axis's health figures over its last cycles in the history, oldest first.
struct HealthTrend {
  std::size_t axis = 0;
  std::string unit;  // "mm" or "deg": the kind the axis moves with in the stored settings
  std::vector<persistence::HealthRecord> cycles;
};
std::expected<HealthTrend, std::string> read_health_trend(const std::string& db, std::size_t axis,
                                                          std::size_t cycles);
std::string trend_table(const HealthTrend& t);
nlohmann::json trend_json(const HealthTrend& t);
// A plot per figure the cycles measured, against the run (trend_svg.cpp).
std::string trend_svg(const HealthTrend& t);

}  // namespace homingctl
