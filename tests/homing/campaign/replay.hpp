#pragma once
// Replays one campaign seed as a named scenario. A failing run prints its
// seed; paste it into a TEST_CASE that names the bug:
//
//   TEST_CASE("gantry racks when the slave's sensor is dead (seed 12345)", "[replay]") { replay_seed(12345); }
//
// A seed stands for a machine only as long as the generator draws the same
// way: when machine_gen.cpp changes, re-pin the replays with the seeds the
// campaign then prints.
#include <catch2/catch.hpp>

#include <cstdio>

#include "run.hpp"

inline void replay_seed(std::uint64_t seed) {
  const campaign::Outcome o = campaign::run_seed(seed);
  if (o.failed) std::printf("\n%s", campaign::report(o).c_str());
  CHECK(o.failure.what == "");
}
