// Quietness: what lets the runtime run its periods far apart while idle
// (server/control_loop.hpp). The engine is quiet only when time alone moves
// nothing on; the simulator tells how long it stays as it is.
#include <catch2/catch.hpp>

#include <cmath>

#include "rig.hpp"

using namespace homing;

TEST_CASE("an engine at rest is quiet, and not while a jog runs or stops") {
  rig::Rig r;
  r.step();
  r.step();
  CHECK(r.engine.quiet());
  CHECK(std::isinf(r.sim().quiet_for_s(r.engine.outputs())));
  r.jog(0, +1);
  r.step();
  CHECK_FALSE(r.engine.quiet());
  r.run_for(0.1);
  CHECK_FALSE(r.engine.quiet());
  CHECK(r.sim().quiet_for_s(r.engine.outputs()) == 0);  // the carriage moves
  r.release_jogs();
  r.step();
  CHECK_FALSE(r.engine.quiet());  // braking
  REQUIRE(r.run_until([&] { return r.engine.quiet(); }, 5));
  CHECK_FALSE(r.any_moving());
  CHECK(std::isinf(r.sim().quiet_for_s(r.engine.outputs())));
}

TEST_CASE("an engine whose home input changed is not quiet until the debounce time has passed") {
  rig::Rig r;
  r.settings.axes[0].debounce_ms = 20;
  r.step();
  REQUIRE(r.engine.quiet());
  REQUIRE(r.sim().place(0, -10));  // into the cam: the switch goes active with no motion
  r.step();                        // the simulator runs the period with the edge
  r.step();                        // the engine reads it
  CHECK_FALSE(r.engine.quiet());
  r.run_for(0.015);
  CHECK_FALSE(r.engine.quiet());
  r.run_for(0.010);
  CHECK(r.engine.quiet());
  CHECK(r.axis(0).sensor);
}

TEST_CASE("the simulator at rest is quiet until its next bounce toggle") {
  rig::Rig r;
  r.machine.axes[0].bounce_ms = 30;
  r.settings.axes[0].debounce_ms = 2;
  r.step();
  REQUIRE(r.sim().place(0, -10));
  r.step();  // the edge and its bounce toggles, up to 30 ms after it
  const double left_s = r.sim().quiet_for_s(r.engine.outputs());
  CHECK(left_s > 0);
  CHECK(left_s <= 0.030);
  r.run_for(0.035);
  CHECK(std::isinf(r.sim().quiet_for_s(r.engine.outputs())));
}

TEST_CASE("the simulator is not quiet while an output moves a carriage or a drive homes") {
  sim::Simulator s(sim::MachineConfig{});
  Outputs out{};
  CHECK(std::isinf(s.quiet_for_s(out)));
  out.axes[1].motion = velocity_command(10, 100);
  CHECK(s.quiet_for_s(out) == 0);
  out = Outputs{};
  out.axes[2].drive_request = true;  // a home request the drive has yet to answer
  CHECK(s.quiet_for_s(out) == 0);
}

TEST_CASE("the simulator is quiet until a locking indexer's pin moves") {
  sim::MachineConfig m{};
  m.indexer[0] = true;  // fitted: starts locked
  m.axes[0].unlock_delay_ms = 50;
  sim::Simulator s(m);
  Outputs out{};
  CHECK(std::isinf(s.quiet_for_s(out)));
  out.axes[0].indexer_unlock = true;
  s.advance(out, 0.010);
  CHECK(s.quiet_for_s(out) == Approx(0.040));
  s.advance(out, 0.040);
  CHECK_FALSE(s.indexer_locked(0));
  CHECK(std::isinf(s.quiet_for_s(out)));
}
