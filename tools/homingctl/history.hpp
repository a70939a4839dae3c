#pragma once
// Recent homing runs and settings changes from the daemon's SQLite file, opened
// read-only (the daemon does not serve its history over Modbus; SQLite's WAL
// lets this reader run next to the daemon).
#include <cstddef>
#include <expected>
#include <string>

#include <nlohmann/json.hpp>

namespace homingctl {

struct HistoryReport {
  std::string text;
  nlohmann::json json;
};

std::expected<HistoryReport, std::string> read_history(const std::string& db, std::size_t runs, std::size_t changes);

}  // namespace homingctl
