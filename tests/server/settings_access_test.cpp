// Settings files (offline export/import on the daemon's database), the
// write allow-list and the settings lock, against the real homingd.
#include <catch2/catch.hpp>

#include <fstream>
#include <regex>

#include "daemon.hpp"
#include "registers/errors.hpp"

using namespace e2e;

namespace {

// The value of `key` in an exported file (a line "key = value  # unit").
std::string replace_line(const std::string& text, const std::string& key, const std::string& value) {
  return std::regex_replace(text, std::regex("\n" + key + " = [^\n]*"), "\n" + key + " = " + value);
}

}  // namespace

TEST_CASE("settings exported from one module's database import onto another and survive its start") {
  TempDir dir;
  const std::string a = dir.file("a.db"), b = dir.file("b.db"), file = dir.file("machine.toml");
  {
    Daemon d({.db = a});
    Client c = Client::tcp(d.port());
    c.set("axis.x.pull_off", um(2.5));
    c.set("axis.y.seek_feedrate", 1500);
    REQUIRE(d.stop() == 0);
  }
  const RunResult exported = run_program({homingd_path(), "--db", a, "--export-settings", file}, 20s);
  REQUIRE(exported.code() == 0);
  const std::string text = read_file(file);
  CHECK(text.find("\naxis.x.pull_off = 2.5  # mm\n") != std::string::npos);  // engineering units

  const RunResult imported = run_program({homingd_path(), "--db", b, "--import-settings", file}, 20s);
  REQUIRE(imported.code() == 0);
  CHECK(imported.out.find("axis.x.pull_off") != std::string::npos);
  Daemon d({.db = b});
  Client c = Client::tcp(d.port());
  CHECK(c.read("axis.x.pull_off") == um(2.5));
  CHECK(c.read("axis.y.seek_feedrate") == 1500);
}

TEST_CASE("an export of a database that is not there is refused and writes nothing: a backup of defaults is none") {
  TempDir dir;
  const std::string db = dir.file("typo.db"), file = dir.file("backup.toml");
  const RunResult r = run_program({homingd_path(), "--db", db, "--export-settings", file}, 20s);
  CHECK(r.code() == 1);
  CHECK(r.err.find("no settings database at " + db) != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(file));
  CHECK_FALSE(std::filesystem::exists(db));
  CHECK_FALSE(std::filesystem::exists(db + ".lock"));
}

TEST_CASE("a settings file of raw register values (format_version 1) still imports") {
  TempDir dir;
  const std::string db = dir.file("m.db"), file = dir.file("old.toml");
  std::ofstream(file) << "format = \"homing-module-settings\"\nformat_version = 1\n\n[settings]\n"
                         "\"axis.x.pull_off\" = 3000\n\"axis.x.direction\" = 1\n";
  const RunResult r = run_program({homingd_path(), "--db", db, "--import-settings", file}, 20s);
  REQUIRE(r.code() == 0);
  Daemon d({.db = db});
  Client c = Client::tcp(d.port());
  CHECK(c.read("axis.x.pull_off") == um(3.0));
  CHECK(c.read("axis.x.direction") == 1);
}

TEST_CASE("an imported file that a Modbus write would refuse changes nothing and names the setting") {
  TempDir dir;
  const std::string db = dir.file("m.db"), file = dir.file("bad.toml");
  {
    Daemon d({.db = db});  // a module's database, on its defaults
    REQUIRE(d.stop() == 0);
  }
  REQUIRE(run_program({homingd_path(), "--db", db, "--export-settings", file}, 20s).code() == 0);
  const std::string good = read_file(file);
  {
    std::ofstream(file) << replace_line(replace_line(good, "axis.x.pull_off", "3.0"), "axis.x.seek_feedrate",
                                        "60000.0");
  }
  const RunResult r = run_program({homingd_path(), "--db", db, "--import-settings", file}, 20s);
  CHECK(r.code() == 1);
  CHECK(r.err.find("max_stop_distance") != std::string::npos);
  CHECK(r.err.find("nothing changed") != std::string::npos);
  Daemon d({.db = db});
  Client c = Client::tcp(d.port());
  CHECK(c.read("axis.x.pull_off") == um(1.0));  // the valid line of the bad file was not applied either
  CHECK(c.read("axis.x.seek_feedrate") == 1000);
}

TEST_CASE("a client outside --write-allow may read but every write is refused with exception 01") {
  Daemon d({.extra = {"--write-allow", "10.1.2.0/24"}});
  Client c = Client::tcp(d.port());
  CHECK(c.read("axis.x.seek_feedrate") == 1000);
  CHECK(c.write("axis.x.seek_feedrate", 1200) == 1);
  CHECK(c.write("cmd.home_all", 1) == 1);
  CHECK(c.read("axis.x.seek_feedrate") == 1000);
  CHECK(c.read("status.homing") == 0);
}

TEST_CASE("a client inside --write-allow writes as usual") {
  Daemon d({.extra = {"--write-allow", "10.1.2.0/24,127.0.0.0/8"}});
  Client c = Client::tcp(d.port());
  CHECK(c.write("axis.x.seek_feedrate", 1200) == 0);
  CHECK(c.read("axis.x.seek_feedrate") == 1200);
}

TEST_CASE("locked settings refuse writes with exception 04 until the unlock code is written") {
  Daemon d({.extra = {"--unlock-code", "4321"}});
  Client c = Client::tcp(d.port());
  CHECK(c.read("status.settings_locked") == 1);
  CHECK(c.write("axis.x.seek_feedrate", 1200) == 4);
  CHECK(c.read("axis.x.seek_feedrate") == 1000);
  // Commands and host values are not settings: they still work while locked.
  CHECK(c.write("host.heartbeat", 7) == 0);

  CHECK(c.write("security.unlock", 1111) == 3);  // wrong code
  CHECK(c.read("status.settings_locked") == 1);
  CHECK(c.write("security.unlock", 4321) == 0);
  CHECK(c.read("status.settings_locked") == 0);
  CHECK(c.read("security.unlock") == 0);  // the code is never read back
  CHECK(c.write("axis.x.seek_feedrate", 1200) == 0);
  CHECK(c.read("axis.x.seek_feedrate") == 1200);

  CHECK(c.write("cmd.lock_settings", 1) == 0);
  CHECK(c.read("status.settings_locked") == 1);
  CHECK(c.write("axis.x.seek_feedrate", 1300) == 4);
  CHECK(c.read("axis.x.seek_feedrate") == 1200);
}

TEST_CASE("without an unlock code the settings are never locked and cmd.lock_settings says so with exception 03") {
  Daemon d;
  Client c = Client::tcp(d.port());
  CHECK(c.read("status.settings_locked") == 0);
  CHECK(c.write("cmd.lock_settings", 1) == 3);
  CHECK(c.read("status.last_refusal_reason") == static_cast<int>(registers::RefusalReason::no_unlock_code));
  CHECK(c.read("status.settings_locked") == 0);
  CHECK(c.write("axis.x.seek_feedrate", 1200) == 0);
}

TEST_CASE("diagnostics show the control loop running and the daemon's memory") {
  Daemon d;
  Client c = Client::tcp(d.port());
  // Idle, the loop runs a period at its slow tick (50 ms, docs/architecture.md).
  const auto periods = c.read("diag.loop_periods");
  CHECK(wait_until([&] { return c.read("diag.loop_periods") > periods + 20; }, 10s));
  CHECK(c.read("diag.rss_kb") > 1000);
  CHECK(c.read("diag.engine_step_ns") > 0);
  CHECK(c.read("diag.tcp_clients") == 1);
  {
    Client second = Client::tcp(d.port());
    CHECK(wait_until([&] { return c.read("diag.tcp_clients") == 2; }, 5s));
  }
  CHECK(wait_until([&] { return c.read("diag.tcp_clients") == 1; }, 5s));

  // The lateness figures are measured: a daemon held stopped for a known time
  // starts its next control period that late, less the rest of the idle
  // wait it was in when stopped (up to a slow tick), which the maximum shows,
  // while one late period among dozens leaves the median where it was. (The
  // sleep makes the stall; nothing waits on it.)
  REQUIRE(wait_until([&] { return c.read("diag.loop_periods") > periods + 60; }, 30s));
  constexpr std::int64_t kStallUs = 300'000;
  REQUIRE(kill(d.pid(), SIGSTOP) == 0);
  std::this_thread::sleep_for(std::chrono::microseconds(kStallUs));
  REQUIRE(kill(d.pid(), SIGCONT) == 0);
  const auto after_stall = c.read("diag.loop_periods");
  REQUIRE(wait_until([&] { return c.read("diag.loop_periods") > after_stall + 10; }, 10s));
  const auto late = c.read_together(
      {"diag.loop_late_p50_us", "diag.loop_late_p99_us", "diag.loop_late_p999_us", "diag.loop_late_max_us"});
  INFO("p50 " << late[0] << " p99 " << late[1] << " p99.9 " << late[2] << " max " << late[3] << " us");
  // Less what passes before the stop takes hold of a loaded machine's threads
  // (1.5 ms was seen on a fresh clone under ctest -j2) and the period due
  // just before it: 20 ms, still some 2,000 times the normal p99.
  constexpr std::int64_t kMarginUs = 20'000;
  constexpr std::int64_t kQuietTickUs = 50'000;  // server::ControlLoop::kQuietTickMs
  CHECK(late[3] >= kStallUs - kQuietTickUs - kMarginUs);
  CHECK(late[0] < kStallUs - kQuietTickUs - kMarginUs);
}

TEST_CASE("status.command_count moves with every command, so a result is matched to its command") {
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto n0 = c.read("status.command_count");
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") == n0 + 1; }, 3s));
  CHECK(c.read("status.last_command_result") == 1);  // accepted
  REQUIRE(c.write("sim.estop", 1) == 0);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") == n0 + 2; }, 3s));
  CHECK(c.read("status.last_command_result") == 4);  // refused_estop
}

TEST_CASE("axis.<a>.alarm_value gives the figure the alarm text quotes") {
  Daemon d;
  Client c = Client::tcp(d.port());
  c.set("axis.x.max_seek_travel", um(40));
  c.set("sim.x.fault", 2);  // sensor stuck inactive
  REQUIRE(c.write("cmd.home.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("axis.x.alarm") != 0; }, 20s));
  CHECK(c.read("axis.x.alarm") == 1);  // sensor_not_found
  CHECK(std::abs(c.read("axis.x.alarm_value") - um(40)) <= 1);
  REQUIRE(c.write("sim.x.fault", 0) == 0);
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("axis.x.alarm") == 0; }, 3s));
  CHECK(c.read("axis.x.alarm_value") == 0);
}
