#include "coverage.hpp"

#include <algorithm>
#include <cstdio>
#include <vector>

namespace campaign {

void Coverage::add(const RunCoverage& run) {
  for (const auto& [key, bits] : run) {
    CoverageRow& row = rows_[key];
    if (bits & seen::present) ++row.runs;
    if (bits & seen::homed) ++row.homed;
    if (bits & seen::alarmed) ++row.alarmed;
    if (bits & seen::refused) ++row.refused;
  }
}

std::string Coverage::table() const {
  std::string out =
      "coverage (runs in which each was present / homed / alarmed / refused; a cause: present / -- / showed its own "
      "alarm / --; a measurement or a reference check: present / judged against the machine's truth / alarmed / --)\n";
  char line[256];
  for (const auto& [key, r] : rows_) {
    std::snprintf(line, sizeof line, "  %-78s %7llu %7llu %7llu %7llu\n", key.c_str(), static_cast<unsigned long long>(r.runs),
                  static_cast<unsigned long long>(r.homed), static_cast<unsigned long long>(r.alarmed),
                  static_cast<unsigned long long>(r.refused));
    out += line;
  }
  return out;
}

namespace {

// What every campaign of at least kFloorRuns runs must reach, as fractions of
// its runs: well below what the generator draws (a third or less), so that
// only a generator that stops drawing something, or an engine that stops
// homing or alarming it, falls short.
struct Floor {
  const char* key;
  double present, homed, alarmed, refused;
};
constexpr Floor kFloors[] = {
    {"mode manual", 0.03, 0.02, 0, 0},
    {"mode switch_release", 0.10, 0.06, 0.01, 0.005},
    {"mode switch_reapproach", 0.10, 0.06, 0.01, 0.005},
    {"mode switch_index", 0.05, 0.03, 0.005, 0.002},
    {"mode absolute", 0.03, 0.02, 0, 0},
    {"mode absolute_final", 0.03, 0.02, 0, 0},
    {"mode pushing_release", 0.03, 0.02, 0.003, 0},
    {"mode pushing_reapproach", 0.03, 0.02, 0.003, 0},
    {"mode drive", 0.03, 0.02, 0.003, 0},
    {"limit switches fitted", 0.05, 0.03, 0.003, 0},
    {"hard_stop by following error", 0.04, 0.02, 0.003, 0},
    {"cause an axis's reversed encoder", 0.003, 0, 0.001, 0},
    {"cause an axis's invalid encoder for the stop", 0.001, 0, 0.0005, 0},
    {"mode home_cam", 0.10, 0.05, 0.01, 0.005},
    {"home_cam starting with the cam ahead", 0.03, 0.015, 0, 0},
    {"home_cam starting with the cam behind", 0.03, 0.015, 0, 0},
    {"home_cam starting on the cam", 0.03, 0.015, 0, 0},
    {"home_cam reversed at a limit switch", 0.03, 0, 0, 0},
    {"home_cam cam_edge ahead", 0.05, 0.02, 0, 0},
    {"home_cam cam_edge behind", 0.05, 0.02, 0, 0},
    {"home_cam limit switches NC", 0.03, 0.01, 0, 0},
    {"cause an axis's cam beyond its limit switches", 0.01, 0, 0.005, 0},
    {"cause an axis's dead cam sensor", 0.01, 0, 0.005, 0},
    {"cause an axis's cam sensor stuck active", 0.005, 0, 0.002, 0},
    {"cause an axis's dead limit switches with its cam behind", 0.004, 0, 0.002, 0},
    {"cause an axis's limit switch within its latch or pull-off", 0.01, 0, 0.005, 0},
    {"a limit switch within jogs, moves or the final move", 0.05, 0, 0, 0},
    {"jogged into a limit switch", 0.01, 0, 0.01, 0},
    {"moved into a limit switch", 0.01, 0, 0.01, 0},
    {"cause an axis's final position beyond its limit switch", 0.005, 0, 0.004, 0},
    {"cause an axis's pre-move past its limit switch", 0.003, 0, 0.002, 0},
    {"cause an axis's limit switches stuck active", 0.01, 0, 0.005, 0},
    {"cause an axis's drive never reporting home done", 0.002, 0, 0.001, 0},
    {"cause an axis's drive answering at once", 0.001, 0, 0.0005, 0},
    {"cause an axis's drive answering after its time limit", 0.001, 0, 0.0005, 0},
    {"cause drive's home done lost", 0.001, 0, 0.0005, 0},
    {"gantry software-slaved", 0.10, 0.05, 0.01, 0.005},
    {"gantry external commutator", 0.08, 0.03, 0.01, 0.003},
    {"gantry external commutator, master switch_index", 0.01, 0.004, 0, 0},
    {"cause the abort", 0.005, 0, 0.004, 0},
    {"cause the e-stop", 0.005, 0, 0.004, 0},
    {"cause drive fault", 0.005, 0, 0.004, 0},
    {"cause sensor stuck active", 0.005, 0, 0.001, 0},
    {"cause sensor stuck inactive", 0.005, 0, 0.001, 0},
    {"cause wire break", 0.005, 0, 0.001, 0},
    {"cause the communication loss", 0.005, 0, 0.002, 0},
    {"cause the permit withdrawn", 0.003, 0, 0.002, 0},
    {"cause an axis's faulty sensor", 0.02, 0, 0.01, 0},
    {"cause an axis's cam shorter than its stop", 0.01, 0, 0.005, 0},
    {"cause an axis's skew beyond its max misalignment", 0.03, 0, 0.01, 0},
    {"cause an axis's invalid absolute encoder", 0.005, 0, 0.003, 0},
    {"cause the configuration check's refusal", 0.05, 0, 0.05, 0},
    {"cause an axis's indexer stuck locked", 0.02, 0, 0.01, 0},
    {"cause an axis's indexer that never locks", 0.02, 0, 0.003, 0},
    {"cause indexer stuck locked", 0.02, 0, 0.01, 0},
    {"cause indexer never locks", 0.02, 0, 0.005, 0},
    {"jog and move before homing, allowed_without_homing all", 0.05, 0, 0, 0},
    {"jog and move before homing, allowed_without_homing jog_reduced", 0.01, 0, 0, 0},
    {"jog and move before homing, allowed_without_homing none", 0.01, 0, 0, 0},
    {"event aimed at phase seek", 0.01, 0, 0, 0},
    {"event aimed at phase stop", 0.005, 0, 0, 0},
    {"event aimed at phase back_off", 0.005, 0, 0, 0},
    {"event aimed at phase pull_off", 0.005, 0, 0, 0},
    {"event aimed at phase reapproach", 0.002, 0, 0, 0},
    {"event aimed at phase push", 0.001, 0, 0, 0},
    {"event aimed at phase index", 0.001, 0, 0, 0},
    {"event aimed at phase waiting", 0.002, 0, 0, 0},
    {"event aimed at phase final_move", 0.002, 0, 0, 0},
    {"settings written: seek feedrate", 0.01, 0, 0, 0},
    {"settings written: origin moved", 0.02, 0, 0, 0},
    {"failure policy stop_all", 0.2, 0, 0, 0},
    {"failure policy finish_independent", 0.2, 0, 0.08, 0},
    {"failure policy finish_independent: axes finished after a failure", 0.04, 0, 0, 0},
    {"failure policy return_to_start", 0.2, 0, 0.08, 0},
    {"failure policy return_to_start: axes went back after a failure", 0.06, 0, 0, 0},
    {"jog interrupted", 0.02, 0, 0.01, 0},
    // About 1% of runs (0.8 to 1.2% on fresh seeds since the home cam draws, which home fewer machines).
    {"move interrupted", 0.003, 0, 0.002, 0},
    // The service acts (service_acts.cpp): measurements drawn, refused as the
    // docs say, judged against the simulated machine's far end; restarts of
    // the daemon, reference checks refused, and accepted or refused from
    // where the carriages really stand.
    // (About 3.3% of runs measure to a limit switch, 3.3% to a hard stop, half
    // of each judged clean; 2% raise travel_end_not_found: 2,000 fresh seeds.)
    {"measurement to a limit switch", 0.01, 0.005, 0, 0},
    {"measurement to a hard stop", 0.01, 0.005, 0, 0},
    {"cause measurement: the far end beyond max_seek_travel", 0.005, 0, 0.005, 0},
    {"measurement refused: refused_no_travel_end", 0.05, 0, 0, 0},
    {"measurement refused: refused_gantry_pair", 0.02, 0, 0, 0},
    {"measurement refused: refused_invalid", 0.015, 0, 0, 0},
    {"measurement refused: refused_home_all_only", 0.008, 0, 0, 0},
    {"restart after a clean stop", 0.06, 0, 0, 0},
    {"restart after a kill", 0.01, 0, 0, 0},
    {"reference check accepted, carriage where it stopped", 0.025, 0.025, 0, 0},
    {"reference check accepted, carriage moved by hand within the tolerance", 0.006, 0.006, 0, 0},
    {"reference check refused, carriage moved by hand beyond the tolerance", 0.008, 0.008, 0, 0},
    {"reference check refused: refused_no_clean_stop", 0.01, 0, 0, 0},
    {"reference check refused: refused_no_switch_edge", 0.03, 0, 0, 0},
    {"reference check refused: refused_gantry_pair", 0.015, 0, 0, 0},
};

}  // namespace

std::string Coverage::shortfalls(std::uint64_t runs) const {
  std::string out;
  const double n = static_cast<double>(runs);
  for (const Floor& f : kFloors) {
    const auto it = rows_.find(f.key);
    const CoverageRow r = it == rows_.end() ? CoverageRow{} : it->second;
    auto below = [&](const char* what, std::uint64_t got, double floor) {
      if (static_cast<double>(got) < floor * n) {
        char line[256];
        std::snprintf(line, sizeof line, "%s: %s in %llu runs, floor %.0f of %llu\n", f.key, what,
                      static_cast<unsigned long long>(got), floor * n, static_cast<unsigned long long>(runs));
        out += line;
      }
    };
    below("present", r.runs, f.present);
    below("homed", r.homed, f.homed);
    below("alarmed", r.alarmed, f.alarmed);
    below("refused", r.refused, f.refused);
  }
  return out;
}

}  // namespace campaign
