// homingctl finds the local homingd through its config file: what it reads,
// what wins, what it refuses (tools/homingctl/local_daemon.hpp).
#include <catch2/catch.hpp>

#include <fstream>

#include "daemon.hpp"
#include "local_daemon.hpp"
#include "notify_socket.hpp"

using namespace homingctl;
using namespace std::chrono_literals;

namespace {

std::string write(const e2e::TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = dir.file(name);
  std::ofstream(path) << text;
  return path;
}

LocalDaemon read_named(const std::string& path) {
  auto r = read_local_daemon({path, true});
  REQUIRE(r);
  REQUIRE(*r);
  return **r;
}

}  // namespace

TEST_CASE("homingctl local daemon: a wildcard listen address is reached on loopback, with the config's unit ids, word order and db") {
  e2e::TempDir dir;
  const auto d = read_named(write(dir, "homingd.toml",
                                  "tcp = \"0.0.0.0:502\"\nunit = 7\nsim-unit = 200\nword_order = \"low-first\"\n"
                                  "db = \"/var/lib/homingd/homingd.db\"\nbackend = \"sim\"\n"));
  CHECK(d.tcp == "127.0.0.1:502");
  CHECK(d.unit == 7);
  CHECK(d.sim_unit == 200);
  CHECK(d.word_order == registers::WordOrder::low_first);
  CHECK(d.db == "/var/lib/homingd/homingd.db");
}

TEST_CASE("homingctl local daemon: a named host is kept, a config without tcp means homingd's default, no_tcp means no address") {
  e2e::TempDir dir;
  CHECK(read_named(write(dir, "a.toml", "tcp = \"10.1.2.3:1503\"\n")).tcp == "10.1.2.3:1503");
  CHECK(read_named(write(dir, "b.toml", "unit = 3\n")).tcp == "127.0.0.1:1502");
  CHECK_FALSE(read_named(write(dir, "c.toml", "no_tcp = true\nrtu = \"/dev/ttyUSB0\"\n")).tcp);
  CHECK(read_named(write(dir, "d.toml", "unit = \"4\"\n")).unit == 4);
}

TEST_CASE("homingctl local daemon: what the command line gives wins over the config file") {
  LocalDaemon local;
  local.tcp = "127.0.0.1:502";
  local.unit = 7;
  local.sim_unit = 200;
  local.word_order = registers::WordOrder::low_first;
  local.db = "/var/lib/homingd/homingd.db";

  ConnectionOptions co;
  std::string db = "homingd.db";
  apply_local_daemon(local, GivenOptions{}, co, db);
  CHECK(co.tcp == "127.0.0.1:502");
  CHECK(co.unit == 7);
  CHECK(co.sim_unit == 200);
  CHECK(co.word_order == registers::WordOrder::low_first);
  CHECK(db == "/var/lib/homingd/homingd.db");

  ConnectionOptions given;
  given.tcp = "192.168.0.9:1502";
  given.unit = 2;
  std::string given_db = "mine.db";
  apply_local_daemon(local, GivenOptions{true, true, false, true, true}, given, given_db);
  CHECK(given.tcp == "192.168.0.9:1502");
  CHECK(given.unit == 2);
  CHECK(given.sim_unit == 200);
  CHECK(given.word_order == registers::WordOrder::high_first);
  CHECK(given_db == "mine.db");
}

TEST_CASE("homingctl local daemon: the file is --daemon-config, else HOMINGD_CONFIG, else the packaged one") {
  {
    notify_test::ScopedEnv env("HOMINGD_CONFIG", std::nullopt);
    const auto c = choose_daemon_config("");
    CHECK(c.path == "/etc/homingd/homingd.toml");
    CHECK_FALSE(c.named);
  }
  notify_test::ScopedEnv env("HOMINGD_CONFIG", "/srv/cell-4/homingd.toml");
  CHECK(choose_daemon_config("").path == "/srv/cell-4/homingd.toml");
  CHECK(choose_daemon_config("").named);
  CHECK(choose_daemon_config("/tmp/x.toml").path == "/tmp/x.toml");
}

TEST_CASE("homingctl local daemon: a missing packaged file means no local daemon, a missing or broken named file is an error naming it") {
  e2e::TempDir dir;
  const std::string missing = dir.file("nothing-here.toml");
  auto quiet = read_local_daemon({missing, false});
  REQUIRE(quiet);
  CHECK_FALSE(*quiet);

  auto named = read_local_daemon({missing, true});
  REQUIRE_FALSE(named);
  CHECK_THAT(named.error(), Catch::Contains(missing));

  const std::string broken = write(dir, "broken.toml", "tcp = \"0.0.0.0:502\"\nword_order = \"middle-first\"\n");
  auto bad = read_local_daemon({broken, true});
  REQUIRE_FALSE(bad);
  CHECK_THAT(bad.error(), Catch::Contains(broken) && Catch::Contains("word_order"));

  const std::string garbled = write(dir, "garbled.toml", "tcp = \n");
  REQUIRE_FALSE(read_local_daemon({garbled, true}));

  // A unit id that is no whole number, or too large for one, is named (1e44 was once converted out of range).
  for (const char* unit : {"1e44", "2.5", "99999999999"}) {
    INFO(unit);
    const std::string odd = write(dir, "odd.toml", std::string("unit = ") + unit + "\n");
    auto r = read_local_daemon({odd, true});
    REQUIRE_FALSE(r);
    CHECK_THAT(r.error(), Catch::Contains(odd) && Catch::Contains("unit is"));
  }
}

TEST_CASE("homingctl finds the daemon its HOMINGD_CONFIG names without --tcp, and a missing named config exits 2") {
  e2e::Daemon d;
  e2e::TempDir dir;
  const std::string config =
      write(dir, "homingd.toml", "tcp = \"0.0.0.0:" + std::to_string(d.port()) + "\"\ndb = \"" + d.db() + "\"\n");
  {
    notify_test::ScopedEnv env("HOMINGD_CONFIG", config);
    const auto r = e2e::run_program({HOMINGCTL_PATH, "get", "status.state"}, 20s);
    CHECK(r.code() == 0);
    CHECK_THAT(r.out, Catch::Contains("status.state"));
    const auto h = e2e::run_program({HOMINGCTL_PATH, "history"}, 20s);  // --db from the config
    CHECK(h.code() == 0);
  }
  const auto r = e2e::run_program({HOMINGCTL_PATH, "--daemon-config", dir.file("absent.toml"), "get", "status.state"}, 20s);
  CHECK(r.code() == 2);
  CHECK_THAT(r.err, Catch::Contains("absent.toml"));
}
