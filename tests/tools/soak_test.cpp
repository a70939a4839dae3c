// The short soak run: 8 clients for 20 s against a homingd that homing_soak
// starts itself; zero invariant violations.
#include <catch2/catch.hpp>

#include "tools_helpers.hpp"

#ifndef HOMING_SOAK_PATH
#error "HOMING_SOAK_PATH must be defined"
#endif

using namespace tools_test;

TEST_CASE("homing_soak: 8 clients for 20 s, zero invariant violations") {
  auto r = run_program({HOMING_SOAK_PATH, "--spawn", HOMINGD_PATH, "--clients", "8", "--duration-s", "20", "--seed", "3",
                        "--time-scale", "10"},
                       120s);
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("invariant violations               0") != std::string::npos);
  CHECK(r.out.find("homing cycles completed") != std::string::npos);
  CHECK(r.out.find("latency ms") != std::string::npos);
  CHECK(r.out.find("homingd VmRSS start -> end") != std::string::npos);
  CHECK(r.out.find("unknown") == std::string::npos);  // memory read from /proc
}
