// docs/operating.md "Settings: durable, audited, recoverable": a database damaged while
// homingd was down is found at the next start, the last good backup restored
// (the log says so); with no good backup the module starts on defaults with
// the settings_lost alarm, which blocks homing until cmd.reset_alarm. The
// real daemon, its files damaged between two runs, read over Modbus/TCP.
#include <catch2/catch.hpp>

#include "daemon.hpp"
#include "homing/alarms.hpp"
#include "homing/status.hpp"

using namespace e2e;

namespace {

constexpr std::int64_t kPullOff = 3210;  // µm, not the default

bool contains(const std::string& text, std::string_view what) { return text.find(what) != std::string::npos; }

// Overwrites `bytes` bytes of the file at `offset` with a pattern no SQLite
// page or header has.
void scribble(const std::string& path, std::size_t offset, std::size_t bytes) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  REQUIRE(f);
  f.seekp(static_cast<std::streamoff>(offset));
  const std::string junk(bytes, '\xA5');
  f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  f.flush();
  REQUIRE(f);
}

// A daemon run that stores a setting, lets its backup be written and stops cleanly.
void run_and_store_a_setting(const std::string& db) {
  Daemon d({.db = db});
  Client c = Client::tcp(d.port());
  c.set("axis.x.pull_off", kPullOff);
  // The backup is written off the write path, within a second of the batch.
  REQUIRE(wait_until([&] { return std::filesystem::exists(db + ".bak"); }, 10s, 50ms));
  c.close();
  const auto st = d.stop(SIGTERM);
  REQUIRE(st);
  REQUIRE(WIFEXITED(*st));
  REQUIRE(WEXITSTATUS(*st) == 0);
  REQUIRE_FALSE(std::filesystem::exists(db + "-wal"));  // a clean stop leaves the whole database in the file
}

int result_of(Client& c) { return static_cast<int>(c.read("status.last_command_result")); }

}  // namespace

TEST_CASE("a database damaged while homingd was down is restored from its backup at the next start") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  run_and_store_a_setting(db);

  SECTION("its header overwritten") { scribble(db, 0, 100); }
  SECTION("its pages overwritten") {
    const auto size = std::filesystem::file_size(db);
    REQUIRE(size > 4096);
    scribble(db, 4096, static_cast<std::size_t>(size) - 4096);
  }

  Daemon d({.db = db});
  Client c = Client::tcp(d.port());
  CHECK(c.read("axis.x.pull_off") == kPullOff);
  CHECK(c.read("status.global_alarm") == 0);
  CHECK((c.read("status.interlocks") & homing::interlock::settings_lost) == 0);
  const std::string log = d.log();
  INFO(log);
  CHECK(contains(log, "settings database is damaged"));
  CHECK(contains(log, "restored from backup " + db + ".bak"));
  CHECK_FALSE(contains(log, "settings_lost"));
}

TEST_CASE("a damaged database without a good backup starts on defaults with settings_lost, which blocks homing until reset") {
  TempDir dir;
  const std::string db = dir.file("machine.db");
  run_and_store_a_setting(db);
  scribble(db, 0, 100);
  SECTION("no backup at all") {
    std::filesystem::remove(db + ".bak");
    std::filesystem::remove(db + ".bak.1");
  }
  SECTION("the backups damaged too") {
    for (const std::string& bak : {db + ".bak", db + ".bak.1"})
      if (std::filesystem::exists(bak)) scribble(bak, 0, 100);
  }

  Daemon d({.db = db});
  Client c = Client::tcp(d.port());
  CHECK(c.read("axis.x.pull_off") == reg("axis.x.pull_off").default_raw);
  CHECK(c.read("status.global_alarm") == static_cast<int>(homing::AlarmCode::settings_lost));
  CHECK(c.read("status.alarm") == 1);
  CHECK((c.read("status.interlocks") & homing::interlock::settings_lost) != 0);
  {
    // The alarm's line, logged by the daemon's monitor as it sees the alarm, says what to do.
    const bool alarm_logged = wait_until([&] { return contains(d.log(), "alarm settings_lost"); }, 5s);
    const std::string log = d.log();
    INFO(log);
    CHECK(contains(log, "settings database is damaged"));
    CHECK(contains(log, "no good copy found; running on DEFAULT settings"));
    CHECK(alarm_logged);
    CHECK(contains(log, "check every setting, then reset to allow homing"));
  }

  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return result_of(c) == static_cast<int>(homing::CommandResult::refused_alarm); }, 5s));
  CHECK(c.read("status.state") != static_cast<int>(homing::MachineState::homing));

  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.global_alarm") == 0; }, 5s));
  CHECK((c.read("status.interlocks") & homing::interlock::settings_lost) == 0);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  CHECK(wait_until([&] { return c.read("status.state") == static_cast<int>(homing::MachineState::homing); }, 5s));
  REQUIRE(c.write("cmd.abort", 1) == 0);
}
