#pragma once
// Internal: the schema history. Step k upgrades a database from version k to
// k+1; a new database runs every step from 0, so the upgrade path is the path
// every installation has taken. Never edit a released step: append one.
#include <string_view>
#include <vector>

namespace persistence::schema {

struct Step {
  int to_version;
  std::string_view description;
  std::string_view sql;
};

const std::vector<Step>& steps();  // steps()[k] takes version k to k+1

}  // namespace persistence::schema
