#pragma once
// Internal: the schema history. Step k upgrades a database from version k to
// k+1; a new database runs every step from 0, so the upgrade path is the path
// every installation has taken. Never edit a released step: append one.
#include <string_view>
#include <vector>

#include "persistence/error.hpp"

namespace spdlog {
class logger;
}

namespace persistence::sql {
class Db;
}

namespace persistence::schema {

struct Step {
  int to_version;
  std::string_view description;
  std::string_view sql;
};

const std::vector<Step>& steps();  // steps()[k] takes version k to k+1

// Runs the steps from version `from` to kSchemaVersion, each in its own
// transaction with the version it reaches (an upgrade cut short resumes).
Status migrate(sql::Db& db, int from, spdlog::logger& log);

}  // namespace persistence::schema
