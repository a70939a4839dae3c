#pragma once
// Replays one campaign seed. A failing run prints its seed: add it to the
// regression list in replays_test.cpp, and write the bug it found as a
// hand-written scenario on the rig (tests/homing/*_test.cpp) named for the
// behaviour it proves. A seed stands for a machine only as long as the
// generator draws the same way: when machine_gen.cpp changes, the list is
// re-pinned with the seeds the campaign then prints.
#include <catch2/catch.hpp>

#include <cstdio>

#include "run.hpp"

inline void replay_seed(std::uint64_t seed) {
  const campaign::Outcome o = campaign::run_seed(seed);
  if (o.failed) std::printf("\n%s", campaign::report(o).c_str());
  CHECK(o.failure.what == "");
}
