#pragma once
// What the campaign reached, per homing mode, gantry topology and cause: in
// how many runs each was present, homed, alarmed, or was refused by the
// configuration check. Printed after every campaign and held to floors, so a
// generator change that stops drawing something fails instead of going quiet.
#include <cstdint>
#include <map>
#include <string>

namespace campaign {

namespace seen {
inline constexpr std::uint8_t present = 1u << 0;
inline constexpr std::uint8_t homed = 1u << 1;    // a mode or gantry: homed in a clean cycle
inline constexpr std::uint8_t alarmed = 1u << 2;  // a mode or gantry: latched an alarm; a cause: its own alarm showed
inline constexpr std::uint8_t refused = 1u << 3;  // the configuration check refused the run's machine
}  // namespace seen

// One run: key ("mode switch_index", "gantry commutator", "cause the abort") -> seen bits.
using RunCoverage = std::map<std::string, std::uint8_t>;

struct CoverageRow {
  std::uint64_t runs = 0, homed = 0, alarmed = 0, refused = 0;
};

class Coverage {
 public:
  void add(const RunCoverage& run);
  std::string table() const;
  // Floors for a campaign of `runs` runs: each line a row that fell short ("" when none).
  std::string shortfalls(std::uint64_t runs) const;
  const std::map<std::string, CoverageRow>& rows() const { return rows_; }

 private:
  std::map<std::string, CoverageRow> rows_;
};

}  // namespace campaign
