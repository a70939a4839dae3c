// The seeded random campaign over the whole configuration space (issues 13, 21).
//
// Each run builds a random machine from its seed (machine_gen.cpp): all six
// axes, every homing mode, random directions and sensor polarities, sequences
// of 1-6 steps with several axes per step, unsequenced axes, software-slaved
// and external-commutator gantries (switch, re-approach and index masters;
// slaves whose inherited settings differ from their master's), random cams,
// hysteresis, noise, bounce and skews, starts on and off the sensors,
// feedrates and accelerations up to the registers' maxima, every
// allowed_without_homing, settings the configuration check must refuse,
// faults (dead or stuck sensors, wire breaks, drive faults, e-stop, lost
// steps, an invalid absolute encoder; for drive-performed homing a drive that
// never answers, answers at once, answers after its time limit or drops its
// home done) at random moments or aimed at a phase,
// aborts, resets, re-homes, jogs and moves (before homing too, and cut short
// by aborts, e-stops, drive faults and communication losses), settings written
// between cycles, a hard-limit trip, a start button held at power-up,
// commissioning measurements (accepted and refused) and daemon restarts
// followed by reference checks, some carriages moved by hand meanwhile
// (service_acts.cpp), and control periods up to 20 ms late. Every period (watch.cpp) and at the end
// of every cycle (verdict.cpp) it checks against the simulator's truth:
//   - no gantry racks beyond its max misalignment (1 um for the arithmetic,
//     plus exactly what periods later than the guard looks ahead can add:
//     docs/homing-methods.md "Gantries: racking") from where it was last
//     square (a pair an alarm left racked may come back to square and the
//     limit beyond), and a locked pair stays locked (up to its limit when
//     one side's drive faults);
//   - no carriage touches a mechanical stop except at reduced current (the
//     push output on), and no homed carriage passes an enforced soft limit;
//   - nothing moves that its configuration or the script does not move
//     (disabled, unsequenced, manual and absolute axes outside their final
//     move, axes outside the cycle or outside their sequence step, anything
//     when the check refuses the cycle, a refused jog or move);
//   - no velocity change beyond the axis's (the pair's lower) acceleration;
//   - while an alarm is latched, speeds only fall, each axis stops within its
//     stop distance and stays there, except as the failure policy drawn
//     (global.failure_policy, policy_watch.cpp) lets it go on: the independent
//     axes of the running step finish homing, or the axes that moved go back
//     to where the cycle found them, the last step first; the first alarm
//     stays the one reported;
//   - every cycle ends homed or in a named alarm, within its distance and
//     time bounds; each alarm is explained by a cause on the axis it names
//     (or that axis's gantry partner), and each cause that must show raises
//     its own alarm there (verdict.cpp), a drive fault's in the phase it
//     struck; a machine built valid and refused by the rule set fails;
//   - a homed axis has the coordinate its mode defines (switch modes: edge
//     and pull-off, a slave with its own pull-off and compensation; absolute:
//     the encoder; manual and unsequenced: the home position where it stood);
//   - a reset after a hard-limit trip is taken and only a jog away moves;
//   - a measurement reports the travel to where the simulated machine has its
//     far limit switch or hard stop (long by at most its detection lag) and
//     ends where the docs say; one the docs refuse gives their result and
//     moves nothing; after a restart a reference check homes a carriage that
//     stood within its tolerance at its true coordinate, refuses one moved
//     further with the mismatch, and a check the docs refuse moves nothing;
//   - no carriage passes a limit switch by more than its stopping distance, a
//     jog or move into one raises limit_switch, and a home cam's search
//     reverses exactly when it meets the limit switch ahead (watch.cpp).
// What a slave inherits (rules.hpp) is the campaign's own reading of the
// README, not the engine's motion_settings. After every campaign a coverage
// table (coverage.cpp) says per mode, topology and cause in how many runs it
// was present, homed, alarmed or refused; with 1,000 runs or more each row is
// held to a floor. tests/mutants shows the campaign failing on planted bugs.
//
// Run count: HOMING_CAMPAIGN_RUNS (default 1000, the fewest the coverage floors
// hold at: some 34 s of one core in a RelWithDebInfo build since the service
// acts, restarts and measurements, joined; CI's two-core runners under -j2
// took over 300 s for 2000); first seed: HOMING_CAMPAIGN_SEED
// (default 1); run i uses seed first + i. The first failure stops the
// campaign and prints its seed, the machine as a story, what the script did,
// and the command that replays it; its seed joins the regression list
// (replays_test.cpp) and the bug becomes a hand-written scenario. HOMING_CAMPAIGN_TRACE=1 prints
// every phase change of a replayed run. HOMING_CAMPAIGN_SURVEY=1 runs on past
// failures and prints each distinct failure with its first seeds, the
// coverage (how many runs homed a gantry, recovered from a hard-limit trip...)
// and the settings the check refused although generated valid: the way to
// see past a known bug, for every failure still counts and fails the run.
//
// Before a release, run a long campaign from a fresh seed (about 34 ms a
// run: a million runs is some nine and a half hours on one core; split it over cores
// with disjoint seed ranges), e.g.
//   HOMING_CAMPAIGN_RUNS=1000000 HOMING_CAMPAIGN_SEED=$RANDOM$RANDOM build/bin/homing_tests "[campaign]"
#include <catch2/catch.hpp>

#include <cstdio>
#include <cstdlib>
#include <array>
#include <map>

#include "replay.hpp"
#include "run.hpp"

namespace {

std::uint64_t env_u64(const char* name, std::uint64_t fallback) {
  const char* v = std::getenv(name);
  if (!v || !*v) return fallback;
  return std::strtoull(v, nullptr, 10);
}

constexpr const char* kName = campaign::kTestName;

}  // namespace

TEST_CASE(kName, "[campaign]") {
  const std::uint64_t runs = env_u64("HOMING_CAMPAIGN_RUNS", 1000);
  const std::uint64_t first = env_u64("HOMING_CAMPAIGN_SEED", 1);
  const bool survey = env_u64("HOMING_CAMPAIGN_SURVEY", 0) != 0;
  std::uint64_t homed = 0, refused = 0, unexpected = 0, failures = 0, periods = 0, passed_periods = 0;
  std::map<std::string, std::pair<std::uint64_t, std::uint64_t>> classes;  // what -> (count, first seed)
  std::map<std::string, std::string> more_seeds;                          // what -> a few more seeds
  std::map<std::string, std::uint64_t> refusals;
  std::array<std::uint64_t, campaign::act::kCount> acts{};
  campaign::Coverage coverage;
  for (std::uint64_t i = 0; i < runs; ++i) {
    // A long survey says how far it got, so that one cut short still tells
    // which seeds it ran.
    if (survey && i > 0 && i % 5000 == 0)
      std::printf("\nsurvey: %llu runs done (seeds %llu to %llu), %llu failed\n", static_cast<unsigned long long>(i),
                  static_cast<unsigned long long>(first), static_cast<unsigned long long>(first + i - 1),
                  static_cast<unsigned long long>(failures));
    const campaign::Outcome o = campaign::run_seed(first + i);
    periods += o.periods;
    coverage.add(o.coverage);
    for (int k = 0; k < campaign::act::kCount; ++k)
      if (o.acts & (1u << k)) ++acts[static_cast<std::size_t>(k)];
    if (o.ever_homed) ++homed;
    if (o.refused) ++refused;
    if (!o.unexpected_refusal.empty()) {
      ++unexpected;
      refusals.emplace(o.unexpected_refusal.substr(0, o.unexpected_refusal.find(';')), o.seed);
    }
    if (!o.failed) {
      passed_periods += o.periods;
      continue;
    }
    ++failures;
    auto [it, fresh] = classes.emplace(o.failure.what, std::make_pair(0, o.seed));
    if (++it->second.first > 1 && it->second.first <= 6) more_seeds[o.failure.what] += " " + std::to_string(o.seed);
    if (!survey) {
      // Printed whole: the story's lines are long, Catch would wrap them.
      std::printf("\n%s", campaign::report(o, kName).c_str());
      FAIL("campaign run " << i + 1 << " of " << runs << " (seed " << o.seed << ") failed: " << o.failure.what
                           << "; the machine and the replay command are printed above");
    }
    if (fresh) std::printf("\n=== new failure class, seed %llu ===\n%s", static_cast<unsigned long long>(o.seed),
                           campaign::report(o, kName).c_str());
    else if (survey) std::printf("\n=== failure (class seen before), seed %llu: %s\n", static_cast<unsigned long long>(o.seed),
                                 o.failure.what.c_str());
  }
  if (survey) {
    std::printf("\n%llu runs, %llu failed, %llu homed at least once, %llu refused (%llu of them generated valid), %llu periods (%llu per run that passed)\n",
                static_cast<unsigned long long>(runs), static_cast<unsigned long long>(failures),
                static_cast<unsigned long long>(homed), static_cast<unsigned long long>(refused),
                static_cast<unsigned long long>(unexpected), static_cast<unsigned long long>(periods),
                static_cast<unsigned long long>(runs > failures ? passed_periods / (runs - failures) : 0));
    for (const auto& [what, c] : classes)
      std::printf("%6llu  first seed %-8llu %s   (also%s)\n", static_cast<unsigned long long>(c.first),
                  static_cast<unsigned long long>(c.second), what.c_str(), more_seeds[what].c_str());
    std::printf("runs that:");
    for (int k = 0; k < campaign::act::kCount; ++k)
      std::printf(" %s %llu;", campaign::act::name(k), static_cast<unsigned long long>(acts[static_cast<std::size_t>(k)]));
    std::printf("\n");
    for (const auto& [why, seed] : refusals) std::printf("refused valid machine, seed %llu: %s\n", static_cast<unsigned long long>(seed), why.c_str());
  }
  std::printf("\n%s", coverage.table().c_str());
  INFO(runs << " runs: " << homed << " homed at least once, " << refused << " refused by the check");
  CHECK(failures == 0);
  // Coverage: most machines must home, and every mode, topology and cause
  // must be reached, homed and alarmed often enough (a replay of one seed need not).
  if (runs >= 100) CHECK(homed > runs / 4);
  if (runs >= 1000) {
    const std::string short_of = coverage.shortfalls(runs);
    INFO("coverage below its floors:\n" << short_of);
    CHECK(short_of.empty());
  }
}
