// homingd's command line, as a tool or a technician meets it: --help lists
// every option of the spec; a wrong option exits 2 with one line that names
// it; a start-up resource at fault (port taken, serial device missing) exits 1
// and is named too (README, "homingd options": scripts and systemd tell the two
// apart by the code).
#include <catch2/catch.hpp>

#include "daemon.hpp"

using namespace e2e;

namespace {

std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

// The last non-empty line: a start-up failure may follow a few log lines.
std::string last_line(std::string text) {
  while (!text.empty() && text.back() == '\n') text.pop_back();
  const auto nl = text.rfind('\n');
  return nl == std::string::npos ? text : text.substr(nl + 1);
}

}  // namespace

TEST_CASE("homingd --help lists every option of the spec and exits 0") {
  const RunResult r = run_program({homingd_path(), "--help"}, 10s);
  REQUIRE(r.exited());
  CHECK(r.code() == 0);
  for (const char* option : {"--tcp", "--no-tcp", "--rtu", "--baud", "--parity", "--stop-bits", "--unit", "--db",
                             "--backend", "--period-us", "--word-order", "--max-clients", "--idle-timeout-s",
                             "--sim-unit", "--time-scale", "--log-level", "--config"}) {
    INFO(option);
    CHECK(r.out.find(option) != std::string::npos);
  }
}

TEST_CASE("homingd exits 2 with one line naming a wrong option") {
  TempDir dir;
  const std::string db = dir.file("never.db");
  const std::string empty_password = dir.file("empty.pw");
  std::ofstream(empty_password) << "";
  struct Case {
    std::vector<std::string> args;
    std::string names;
  };
  const std::vector<Case> cases{
      {{"--parity", "X"}, "--parity"},
      {{"--baud", "7"}, "--baud"},
      {{"--tcp", "nonsense"}, "--tcp"},
      {{"--tcp", "127.0.0.1:70000"}, "--tcp"},
      {{"--tcp", "127.0.0.1:port"}, "--tcp"},
      // libmodbus would listen on 255.255.255.255 for these, and say nothing
      {{"--tcp", "plc-cabinet:1502"}, "--tcp"},
      {{"--tcp", "192.168.1.300:1502"}, "--tcp"},
      {{"--tcp", "255.255.255.255:1502"}, "--tcp"},
      {{"--stop-bits", "3"}, "--stop-bits"},
      {{"--time-scale", "-1"}, "--time-scale"},
      {{"--unit", "0"}, "--unit"},
      {{"--word-order", "middle"}, "--word-order"},
      {{"--no-such-option"}, "--no-such-option"},
      {{"--no-tcp=trux"}, "--no-tcp"},  // was an uncaught std::invalid_argument (abort), found by fuzz_config
      // read before the database: a refused start must not consume the axes' last stops
      {{"--mqtt", "mqtt://127.0.0.1:1", "--mqtt-user", "m", "--mqtt-password-file", empty_password},
       "--mqtt-password-file"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> argv{homingd_path(), "--db", db};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    const RunResult r = run_program(argv, 10s);
    INFO("args: " << c.args[0] << (c.args.size() > 1 ? " " + c.args[1] : "") << "\nstderr: " << r.err);
    REQUIRE(r.exited());
    CHECK(r.code() == 2);  // a usage error
    CHECK(first_line(r.err).find(c.names) != std::string::npos);
    CHECK(r.out.find("listening") == std::string::npos);
  }
  CHECK_FALSE(std::filesystem::exists(db));  // nothing was created by a refused start
}

TEST_CASE("homingd exits 1 naming the resource at fault when it cannot start") {
  Daemon first;
  TempDir dir;
  SECTION("the TCP port is taken") {
    const RunResult r = run_program({homingd_path(), "--tcp", "127.0.0.1:" + std::to_string(first.port()), "--db",
                                     dir.file("second.db")},
                                    10s);
    INFO("stderr: " << r.err);
    REQUIRE(r.exited());
    CHECK(r.code() == 1);  // a resource that cannot be used
    CHECK(last_line(r.err).find("--tcp") != std::string::npos);
    CHECK(last_line(r.err).find("in use") != std::string::npos);
  }
  SECTION("the serial device does not exist") {
    const RunResult r = run_program({homingd_path(), "--tcp", "127.0.0.1:" + std::to_string(free_port()), "--db",
                                     dir.file("third.db"), "--rtu", dir.file("no-such-tty")},
                                    10s);
    INFO("stderr: " << r.err);
    REQUIRE(r.exited());
    CHECK(r.code() == 1);  // a resource that cannot be used
    CHECK(last_line(r.err).find("--rtu") != std::string::npos);
  }
  SECTION("another homingd runs on the database") {
    const RunResult r = run_program({homingd_path(), "--tcp", "127.0.0.1:" + std::to_string(free_port()), "--db",
                                     first.db()},
                                    10s);
    INFO("stderr: " << r.err);
    REQUIRE(r.exited());
    CHECK(r.code() == 1);
    CHECK(last_line(r.err).find("--db " + first.db() + ": another homingd uses this database (pid " +
                                std::to_string(first.pid()) + ")") != std::string::npos);
    CHECK(r.out.find("listening") == std::string::npos);
  }
  SECTION("a settings import into the database a homingd runs on") {
    const std::string file = dir.file("settings.toml");
    test_support::write_text(file, "format_version = 2\n");
    const RunResult r = run_program({homingd_path(), "--db", first.db(), "--import-settings", file}, 10s);
    INFO("stderr: " << r.err);
    REQUIRE(r.exited());
    CHECK(r.code() == 1);
    CHECK(last_line(r.err).find("another homingd uses this database") != std::string::npos);
    CHECK(last_line(r.err).find("homingctl import FILE") != std::string::npos);
  }
  SECTION("a settings export from the database a homingd runs on names the readers that may") {
    const RunResult r =
        run_program({homingd_path(), "--db", first.db(), "--export-settings", dir.file("out.toml")}, 10s);
    INFO("stderr: " << r.err);
    REQUIRE(r.exited());
    CHECK(r.code() == 1);
    CHECK(last_line(r.err).find("homing-settings --db " + first.db() + " export FILE") != std::string::npos);
    CHECK_FALSE(std::filesystem::exists(dir.file("out.toml")));
  }
  // The first daemon is unharmed and still answers.
  Client c = Client::tcp(first.port());
  CHECK(c.read("status.map_version") == registers::kMapVersion);
  const auto st = first.stop(SIGTERM);
  REQUIRE(st);
  CHECK(WIFEXITED(*st));
  CHECK(WEXITSTATUS(*st) == 0);
}
