// Campaign seeds replayed as named scenarios: each seed's first failure, when
// it was pinned, was the bug its name gives (issue 13). A seed stands for its
// machine only while machine_gen.cpp draws the same way: when the generator
// changes, re-pin these with the seeds the campaign then prints.
#include "replay.hpp"

TEST_CASE("replay: a start button held at power-up starts home-all (seed 1)", "[replay]") { replay_seed(1); }

TEST_CASE("replay: the check refuses a slave for a setting it inherits from its master (seed 7)",
          "[replay]") {
  replay_seed(7);
}

TEST_CASE("replay: a gantry master accelerates at its own rate instead of the pair's lower one (seed 3)",
          "[replay]") {
  replay_seed(3);
}

TEST_CASE("replay: a slave follows its master at an acceleration beyond its own (seed 8)", "[replay]") {
  replay_seed(8);
}

TEST_CASE("replay: the seek stops dead at max seek travel (seed 490)", "[replay]") { replay_seed(490); }

TEST_CASE("replay: the back-off stops dead at max back-off (seed 715)", "[replay]") { replay_seed(715); }

TEST_CASE("replay: a pull-off stops dead on its target after a late period (seed 2)", "[replay]") {
  replay_seed(2);
}

TEST_CASE("replay: the check accepts a gantry whose stop distance exceeds its max misalignment (seed 173)",
          "[replay]") {
  replay_seed(173);
}

TEST_CASE("replay: the check accepts a push distance beyond max back-off (seed 959)", "[replay]") {
  replay_seed(959);
}

TEST_CASE("replay: the check accepts a disabled commutator slave (seed 1242)", "[replay]") {
  replay_seed(1242);
}

TEST_CASE("replay: the check sizes a gantry's stop with the master's acceleration instead of the pair's (seed 2054)",
          "[replay]") {
  replay_seed(2054);
}

TEST_CASE("replay: home-all starts although an unsequenced axis's settings are refused (seed 84)",
          "[replay]") {
  replay_seed(84);
}

TEST_CASE("replay: a slave of a disabled axis follows its jog (seed 4)", "[replay]") { replay_seed(4); }

TEST_CASE("replay: a slave of a manual or absolute axis follows its jog (seed 103)", "[replay]") {
  replay_seed(103);
}

TEST_CASE("replay: a second slave on one master follows its jog (seed 1069)", "[replay]") {
  replay_seed(1069);
}

TEST_CASE("replay: an unsequenced absolute axis is given its home position instead of the encoder's (seed 412)",
          "[replay]") {
  replay_seed(412);
}

TEST_CASE("replay: a software-slaved gantry racks past its limit before braking (seed 627)", "[replay]") {
  replay_seed(627);
}

TEST_CASE("replay: a commutator slave's sensor read with its master's polarity racks the gantry (seed 3972)",
          "[replay]") {
  replay_seed(3972);
}
