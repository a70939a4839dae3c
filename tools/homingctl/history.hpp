#pragma once
// The one reader of the module's history: recent homing runs, settings
// changes and the home corrections per axis, from the daemon's SQLite file
// opened read-only (the daemon does not serve its history over Modbus;
// SQLite's WAL lets this reader run next to the daemon). `homingctl history`
// is its front end.
#include <cstddef>
#include <expected>
#include <string>

#include <nlohmann/json.hpp>

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

}  // namespace homingctl
