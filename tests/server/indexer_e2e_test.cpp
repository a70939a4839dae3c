// The locking indexer over Modbus/TCP with the real homingd and its
// simulator unit: axis.a.indexer_lock fits the simulated indexer, a homing
// cycle unlocks, homes and locks again, and each of its alarms is caused by
// its simulator fault, read with its code and reset.
#include <catch2/catch.hpp>

#include "daemon.hpp"
#include "homing/alarms.hpp"
#include "homing/phases.hpp"
#include "homing/sim/config.hpp"

using namespace e2e;
using homing::AlarmCode;
using homing::Phase;

namespace {

int code(AlarmCode c) { return static_cast<int>(c); }
int code(Phase p) { return static_cast<int>(p); }
int code(homing::sim::Fault f) { return static_cast<int>(f); }

// A homes on its switch (mode 2) 5 deg from the release edge, with a locking
// indexer whose pin takes 200 ms each way and a 1 s lock timeout.
void configure_a(Client& c) {
  REQUIRE(c.write("sim.a.unlock_delay_ms", 200) == 0);
  REQUIRE(c.write("sim.a.lock_delay_ms", 200) == 0);
  REQUIRE(c.write("sim.a.actual_position", 5'000) == 0);
  REQUIRE(c.write("axis.a.mode", 2) == 0);
  REQUIRE(c.write("axis.a.lock_timeout_ms", 1'000) == 0);
  REQUIRE(c.write("axis.a.indexer_lock", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("sim.a.indexer_locked") == 1; }, 2s));
}

bool alarm_is(Client& c, AlarmCode a) { return c.read("axis.a.alarm") == code(a); }

void reset(Client& c) {
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 0; }, 2s));
}

}  // namespace

TEST_CASE("over Modbus a locking indexer unlocks before A homes, holds it still meanwhile and locks it after") {
  Daemon d;
  Client c = Client::tcp(d.port());
  configure_a(c);
  // Each way 800 ms here: under the sanitizers on 2 shared cores one poll of
  // four reads has taken longer than the 200 ms a phase lasts elsewhere.
  REQUIRE(c.write("axis.a.lock_timeout_ms", 3'000) == 0);
  REQUIRE(c.write("sim.a.unlock_delay_ms", 800) == 0);
  REQUIRE(c.write("sim.a.lock_delay_ms", 800) == 0);
  CHECK(c.read("axis.a.phase") == code(Phase::idle));
  REQUIRE(c.write("cmd.home.a", 1) == 0);
  // The first 800 ms: held in phase unlock, the carriage where it was.
  REQUIRE(wait_until([&] { return c.read("axis.a.phase") == code(Phase::unlock); }, 2s));
  CHECK(c.read("sim.a.actual_position") == 5'000);
  CHECK(c.read("sim.a.indexer_locked") == 1);
  bool saw_lock = false;
  REQUIRE(wait_until(
      [&] {
        const auto phase = c.read("axis.a.phase");
        saw_lock = saw_lock || phase == code(Phase::lock);
        return phase == code(Phase::done) && c.read("axis.a.homed") == 1 &&
               c.read("sim.a.indexer_locked") == 1;
      },
      20s, 20ms));
  CHECK(saw_lock);
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("axis.a.position") == 0);
  // At rest and locked it stays so.
  const auto at = c.read("sim.a.actual_position");
  CHECK(c.read("axis.a.busy") == 0);
  CHECK(c.read("sim.a.actual_position") == at);
}

TEST_CASE("over Modbus each locking-indexer alarm is raised by its simulator fault and reset") {
  Daemon d;
  Client c = Client::tcp(d.port());
  configure_a(c);

  SECTION("unlock_not_confirmed: stuck locked, a jog times out without moving") {
    REQUIRE(c.write("sim.a.fault", code(homing::sim::Fault::indexer_stuck_locked)) == 0);
    const auto at = c.read("sim.a.actual_position");
    REQUIRE(c.write("cmd.jog_plus.a", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("status.alarm") == 1; }, 5s));
    CHECK(alarm_is(c, AlarmCode::unlock_not_confirmed));
    CHECK(c.read("axis.a.alarm_phase") == code(Phase::unlock));
    CHECK(c.read("sim.a.actual_position") == at);
    REQUIRE(c.write("cmd.jog_plus.a", 0) == 0);
    REQUIRE(c.write("sim.a.fault", 0) == 0);
    reset(c);
    CHECK(alarm_is(c, AlarmCode::none));
  }

  SECTION("lock_not_confirmed: the pin stays out after a jog") {
    REQUIRE(c.write("sim.a.fault", code(homing::sim::Fault::indexer_never_locks)) == 0);
    REQUIRE(c.write("cmd.jog_plus.a", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("axis.a.phase") == code(Phase::jog); }, 5s));
    REQUIRE(c.write("cmd.jog_plus.a", 0) == 0);
    REQUIRE(wait_until([&] { return c.read("status.alarm") == 1; }, 5s));
    CHECK(alarm_is(c, AlarmCode::lock_not_confirmed));
    CHECK(c.read("axis.a.alarm_phase") == code(Phase::lock));
    CHECK(c.read("sim.a.indexer_locked") == 0);
    REQUIRE(c.write("sim.a.fault", 0) == 0);
    REQUIRE(wait_until([&] { return c.read("sim.a.indexer_locked") == 1; }, 2s));
    reset(c);
    CHECK(alarm_is(c, AlarmCode::none));
  }

  SECTION("lock_engaged: the pin goes in while a jog runs") {
    // Homed, a jog runs unlocked: a fault may strike a moving carriage, and
    // the pin going in is then the alarm.
    REQUIRE(c.write("cmd.home.a", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("axis.a.homed") == 1 && c.read("sim.a.indexer_locked") == 1; }, 20s));
    REQUIRE(c.write("cmd.jog_plus.a", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("axis.a.velocity") > 0; }, 10s));
    CHECK(c.read("axis.a.phase") == code(Phase::jog));
    REQUIRE(c.write("sim.a.fault", code(homing::sim::Fault::indexer_stuck_locked)) == 0);
    REQUIRE(wait_until([&] { return c.read("status.alarm") == 1; }, 2s));
    CHECK(alarm_is(c, AlarmCode::lock_engaged));
    CHECK(c.read("axis.a.alarm_phase") == code(Phase::jog));
    REQUIRE(c.write("cmd.jog_plus.a", 0) == 0);
    REQUIRE(c.write("sim.a.fault", 0) == 0);
    reset(c);
    CHECK(alarm_is(c, AlarmCode::none));
  }
}
