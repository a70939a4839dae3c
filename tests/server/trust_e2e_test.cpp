// Position trust across restarts, end to end over Modbus/TCP with the real
// homingd on one database: homed, stopped with SIGTERM, started again; the
// simulator keeps its carriages as a real machine does. A clean stop offers
// cmd.refcheck.<a>, which homes the axis without a full cycle, or refuses with
// the figure when the carriage was moved through the simulator unit; SIGKILL
// leaves nothing trusted.
#include <catch2/catch.hpp>

#include <cstdlib>

#include "command_wait.hpp"
#include "daemon.hpp"
#include "homing/status.hpp"

using namespace e2e;

namespace {

std::int64_t v(homing::Trust t) { return static_cast<std::int64_t>(t); }
std::int64_t v(homing::CommandResult r) { return static_cast<std::int64_t>(r); }

void stop_cleanly(Daemon& d) {
  const auto st = d.stop(SIGTERM, 30s);
  REQUIRE(st);
  CHECK(WIFEXITED(*st));
  CHECK(WEXITSTATUS(*st) == 0);
}

// Where X was homed to, and where its carriage was, before the stop.
struct Before {
  std::int64_t position_um = 0;
  std::int64_t carriage_um = 0;
};

// A module on `db` homed, then stopped with SIGTERM.
Before home_and_stop(const std::string& db) {
  Daemon d({.db = db});
  Client c = Client::tcp(d.port());
  REQUIRE(command(c, "cmd.home_all") == v(homing::CommandResult::accepted));
  REQUIRE(c.read("status.state") == static_cast<std::int64_t>(homing::MachineState::homed));
  CHECK(c.read("axis.x.trust") == v(homing::Trust::homed_this_power_on));
  const Before b{c.read("axis.x.position"), c.read("sim.x.actual_position")};
  c.close();
  stop_cleanly(d);
  CHECK(d.log().find("last stops kept: 3 axis(es) stopped cleanly") != std::string::npos);
  return b;
}

}  // namespace

TEST_CASE("over Modbus: after a SIGTERM the restarted module trusts X's last stop and cmd.refcheck.x homes it without a full cycle") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  const Before before = home_and_stop(db);

  Daemon d({.db = db});
  Client c = Client::tcp(d.port());
  // Unhomed as always after a start, but its last stop is trusted, and the carriage stayed.
  CHECK(c.read("axis.x.homed") == 0);
  CHECK(c.read("axis.x.trust") == v(homing::Trust::last_stop_clean));
  CHECK(c.read("axis.x.position") == before.position_um);
  CHECK(c.read("sim.x.actual_position") == before.carriage_um);
  CHECK(c.read("axis.a.trust") == v(homing::Trust::unknown));  // disabled, never homed

  CHECK(command(c, "cmd.refcheck.x") == v(homing::CommandResult::accepted));
  CHECK(c.read("axis.x.homed") == 1);
  CHECK(c.read("axis.x.trust") == v(homing::Trust::reference_checked));
  CHECK(std::llabs(c.read("axis.x.refcheck_error")) <= c.read("axis.x.refcheck_tolerance"));
  CHECK(c.read("status.homing_cycles") == 0);  // no full cycle ran
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("sim.x.actual_position") == before.carriage_um);  // back where it stood
  CHECK(std::llabs(c.read("axis.x.position") - before.position_um) <= c.read("axis.x.refcheck_tolerance"));
  // The others still wait for theirs.
  CHECK(c.read("axis.y.trust") == v(homing::Trust::last_stop_clean));
  REQUIRE(wait_until([&] { return d.log().find("reference check of X accepted") != std::string::npos; }, 5s));
}

TEST_CASE("over Modbus: a carriage moved through the simulator unit before the check is refused with the figure and stays unhomed") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  const Before before = home_and_stop(db);

  Daemon d({.db = db});
  Client c = Client::tcp(d.port());
  REQUIRE(c.read("axis.x.trust") == v(homing::Trust::last_stop_clean));
  // Moved 2 mm away from its switch by hand while the module was off.
  c.set("sim.x.actual_position", before.carriage_um + 2000);

  CHECK(command(c, "cmd.refcheck.x") == v(homing::CommandResult::accepted));  // the check ran
  CHECK(c.read("axis.x.homed") == 0);
  CHECK(c.read("axis.x.trust") == v(homing::Trust::unknown));
  CHECK(c.read("axis.x.refcheck_error") == Approx(-2000).margin(20));  // µm: the edge came 2 mm late
  CHECK(c.read("status.alarm") == 0);
  CHECK(c.read("sim.x.actual_position") == before.carriage_um + 2000);  // back where the check found it
  REQUIRE(wait_until([&] { return d.log().find("reference check of X refused") != std::string::npos; }, 5s));
  // Not offered twice: a full cycle is needed, and it homes X.
  CHECK(command(c, "cmd.refcheck.x") == v(homing::CommandResult::refused_no_clean_stop));
  CHECK(command(c, "cmd.home.x") == v(homing::CommandResult::accepted));
  CHECK(c.read("axis.x.trust") == v(homing::Trust::homed_this_power_on));
}

TEST_CASE("a start refused for a port already taken keeps the axes' clean stops for the next start") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  home_and_stop(db);
  {
    Daemon holder;  // another program on the port the next start asks for
    const RunResult r = run_program(
        {homingd_path(), "--db", db, "--tcp", "127.0.0.1:" + std::to_string(holder.port())}, 20s);
    INFO("stderr: " << r.err);
    REQUIRE(r.exited());
    REQUIRE(r.code() == 1);
    CHECK(r.err.find("--tcp") != std::string::npos);
  }
  Daemon again({.db = db});
  Client c = Client::tcp(again.port());
  for (const char* a : {"x", "y", "z"}) CHECK(c.read(std::string("axis.") + a + ".trust") == v(homing::Trust::last_stop_clean));
  CHECK(command(c, "cmd.refcheck.x") == v(homing::CommandResult::accepted));
}

TEST_CASE("over Modbus: after a SIGKILL no axis is trusted, even one that stopped cleanly the time before") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  SECTION("killed while homed") {
    Daemon d({.db = db});
    Client c = Client::tcp(d.port());
    REQUIRE(command(c, "cmd.home_all") == v(homing::CommandResult::accepted));
    REQUIRE(c.read("axis.x.homed") == 1);
    const std::int64_t carriage = c.read("sim.x.actual_position");
    // The simulator keeps its carriages at rest even without a clean stop (as a real machine).
    REQUIRE(wait_until([&] { return d.log().find("homing done") != std::string::npos; }, 5s));
    std::this_thread::sleep_for(500ms);
    c.close();
    d.stop(SIGKILL);
    Daemon again({.db = db});
    Client c2 = Client::tcp(again.port());
    CHECK(c2.read("sim.x.actual_position") == carriage);
    for (const char* a : {"x", "y", "z"}) CHECK(c2.read(std::string("axis.") + a + ".trust") == v(homing::Trust::unknown));
    CHECK(command(c2, "cmd.refcheck.x") == v(homing::CommandResult::refused_no_clean_stop));
    CHECK(c2.read("status.homing") == 0);
  }
  SECTION("stopped cleanly, started again, then killed before anything moved") {
    home_and_stop(db);
    {
      Daemon d({.db = db});
      Client c = Client::tcp(d.port());
      REQUIRE(c.read("axis.x.trust") == v(homing::Trust::last_stop_clean));
      c.close();
      d.stop(SIGKILL);
    }
    Daemon again({.db = db});
    Client c = Client::tcp(again.port());
    CHECK(c.read("axis.x.trust") == v(homing::Trust::unknown));
    CHECK(command(c, "cmd.refcheck.x") == v(homing::CommandResult::refused_no_clean_stop));
  }
}

TEST_CASE("over Modbus: a home position written to a homed axis unhomes it and the log says why and what to do") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  home_and_stop(db);

  Daemon d({.db = db});
  Client c = Client::tcp(d.port());
  REQUIRE(c.read("axis.y.trust") == v(homing::Trust::last_stop_clean));
  c.set("axis.y.pull_off", c.read("axis.y.pull_off") + 500);
  REQUIRE(wait_until([&] { return c.read("axis.y.trust") == v(homing::Trust::unknown); }, 5s));
  REQUIRE(wait_until(
      [&] {
        return d.log().find("axis y: the reference check its clean stop offered is withdrawn: pull_off changed") !=
               std::string::npos;
      },
      5s));
  CHECK(command(c, "cmd.refcheck.y") == v(homing::CommandResult::refused_no_clean_stop));

  REQUIRE(command(c, "cmd.home.x") == v(homing::CommandResult::accepted));
  REQUIRE(c.read("axis.x.homed") == 1);
  c.set("axis.x.home_position", c.read("axis.x.home_position") + 1000);
  REQUIRE(wait_until([&] { return c.read("axis.x.homed") == 0; }, 5s));
  REQUIRE(wait_until(
      [&] {
        return d.log().find("axis x is no longer homed: home_position changed, which places its coordinates; home it "
                            "again") != std::string::npos;
      },
      5s));
  // A setting that places nothing unhomes nothing and says nothing.
  REQUIRE(command(c, "cmd.home.x") == v(homing::CommandResult::accepted));
  c.set("axis.x.seek_feedrate", c.read("axis.x.seek_feedrate") - 100);
  std::this_thread::sleep_for(200ms);
  CHECK(c.read("axis.x.homed") == 1);
  const std::string log = d.log();
  CHECK(log.find("axis x is no longer homed") == log.rfind("axis x is no longer homed"));  // the one line, above
}
