// The campaign fails on purpose-made wrong products: each test plants one
// known bug in the engine (homing/mutation.hpp) and runs the campaign from
// seed 1 until a run fails, which must happen within a bounded number of
// runs and with the failure that bug produces. A campaign whose verdicts
// cannot fail would pass these products.
#include <catch2/catch.hpp>

#include <cstdio>
#include <string>

#include "homing/campaign/run.hpp"
#include "homing/mutation.hpp"

namespace homing {
Mutant& planted_mutant() {
  static Mutant m = Mutant::none;
  return m;
}
}  // namespace homing

namespace {

struct Planted {
  explicit Planted(homing::Mutant m) { homing::planted_mutant() = m; }
  ~Planted() { homing::planted_mutant() = homing::Mutant::none; }
  Planted(const Planted&) = delete;
  Planted& operator=(const Planted&) = delete;
};

// The first failing run of the campaign from seed 1, within max_runs.
campaign::Outcome first_failure(std::uint64_t max_runs) {
  campaign::Outcome o;
  for (std::uint64_t seed = 1; seed <= max_runs; ++seed) {
    o = campaign::run_seed(seed);
    if (o.failed) {
      std::printf("mutant caught at seed %llu: %s\n  %s\n", static_cast<unsigned long long>(seed), o.failure.what.c_str(),
                  o.failure.detail.c_str());
      return o;
    }
  }
  return o;
}

}  // namespace

TEST_CASE("mutation check: the campaign fails a product whose drive fault raises a sensor alarm on another axis",
          "[mutant]") {
  Planted p(homing::Mutant::drive_fault_as_sensor_alarm_elsewhere);
  const campaign::Outcome o = first_failure(500);
  REQUIRE(o.failed);
  CHECK((o.failure.what == "alarm sensor_not_found without a cause on its axis" ||
         o.failure.what == "drive fault raised no alarm of its own"));
}

TEST_CASE("mutation check: the campaign fails a product whose gantry slave homes in its own direction", "[mutant]") {
  Planted p(homing::Mutant::slave_keeps_own_direction);
  const campaign::Outcome o = first_failure(500);
  REQUIRE(o.failed);
  INFO(o.failure.what << ": " << o.failure.detail);
  // The slave seeks away from its sensor: its pair racks, its coordinate is
  // wrong, or a misalignment it should not have stops it.
  const std::string& w = o.failure.what;
  CHECK((w.find("gantry racked") != std::string::npos || w.find("coordinate") != std::string::npos ||
         w.find("without a cause") != std::string::npos || w.find("mechanical stop") != std::string::npos ||
         w.find("travelled beyond") != std::string::npos));
}

TEST_CASE("mutation check: the campaign fails a product that lets a gantry rack 0.2 mm past its limit", "[mutant]") {
  Planted p(homing::Mutant::racking_allowed_0_2_mm_past_limit);
  const campaign::Outcome o = first_failure(1000);
  REQUIRE(o.failed);
  CHECK(o.failure.what.rfind("a gantry racked beyond its max misalignment", 0) == 0);
}

TEST_CASE("mutation check: the campaign fails a product that trusts an encoder counting the wrong way",
          "[mutant]") {
  Planted p(homing::Mutant::reversed_encoder_unchecked);
  const campaign::Outcome o = first_failure(1000);
  REQUIRE(o.failed);
  INFO(o.failure.what << ": " << o.failure.detail);
  // The lag doubles in free air: a hard-stop axis reading its encoder homes
  // short of its stop, or the reversed encoder's own alarm never comes.
  const std::string& w = o.failure.what;
  CHECK((w.find("coordinate") != std::string::npos || w.find("reversed encoder") != std::string::npos));
}

TEST_CASE("mutation check: the campaign fails a product that ignores a limit switch outside homing", "[mutant]") {
  Planted p(homing::Mutant::limit_switch_ignored_outside_homing);
  const campaign::Outcome o = first_failure(500);
  REQUIRE(o.failed);
  INFO(o.failure.what << ": " << o.failure.detail);
  // A jog or move runs on past the switch: beyond its stopping distance, into
  // the mechanical stop, or without the limit_switch alarm it must raise.
  const std::string& w = o.failure.what;
  CHECK((w == "a carriage passed a limit switch by more than its stopping distance" ||
         w.rfind("a carriage ran into a mechanical stop", 0) == 0 || w.find("raised no alarm of its own") != std::string::npos));
}

TEST_CASE("mutation check: the campaign fails a home cam search that seeks on past the limit switch ahead",
          "[mutant]") {
  Planted p(homing::Mutant::home_cam_search_ignores_limit_switch);
  const campaign::Outcome o = first_failure(200);
  REQUIRE(o.failed);
  CHECK(o.failure.what == "the home cam search met the limit switch ahead and sought on");
}

TEST_CASE("mutation check: the campaign fails a software-slaved gantry whose sides turn at their edges a period apart",
          "[mutant]") {
  Planted p(homing::Mutant::gantry_side_turns_alone);
  const campaign::Outcome o = first_failure(500);
  REQUIRE(o.failed);
  INFO(o.failure.what << ": " << o.failure.detail);
  CHECK(o.failure.what == "a software-slaved gantry side turned at its edge without the other");
}

TEST_CASE("mutation check: the same campaign seeds pass on the product as built", "[mutant]") {
  // The mutants above are caught by the campaign, not by a broken harness:
  // without a planted bug the same seeds run clean.
  for (std::uint64_t seed = 1; seed <= 100; ++seed) {
    const campaign::Outcome o = campaign::run_seed(seed);
    INFO("seed " << seed << ": " << o.failure.what);
    REQUIRE_FALSE(o.failed);
  }
}
