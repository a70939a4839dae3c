// Start-up options from a TOML config file (--config), the command line winning.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include "daemon.hpp"

using namespace e2e;

TEST_CASE("options in the config file are used, and the command line wins over them") {
  TempDir dir;
  const std::string config = dir.file("homingd.toml");
  std::ofstream(config) << "# cabinet 7\n"
                           "tcp = \"127.0.0.1:1\"          # overridden by the test's --tcp\n"
                           "unit = 3\n"
                           "sim_unit = 200\n"
                           "word_order = \"low-first\"\n"
                           "max_clients = 8\n"
                           "log_level = \"warn\"\n";
  Daemon d({.extra = {"--config", config}});
  Client c = Client::tcp(d.port(), /*module_unit=*/3, /*sim_unit=*/200);
  // Unit 3 answers; the simulator sits on unit 200.
  CHECK(c.read("axis.x.seek_feedrate") == 1000);
  // low-first: the low word of a 32-bit value comes first on the wire.
  const auto words = c.holding(registers::find_register("axis.x.max_seek_travel")->address, 2);
  REQUIRE(words);
  CHECK(((*words)[1] << 16 | (*words)[0]) == 500000);
  CHECK(c.try_read("sim.x.hysteresis"));  // a one-word register of the simulator unit
  // Unit 1 is not served any more.
  Client other = Client::tcp(d.port(), 1, 247);
  CHECK_FALSE(other.try_read("axis.x.seek_feedrate"));
}

TEST_CASE("an unknown key or a wrong value in the config file stops the start naming it") {
  TempDir dir;
  const std::string typo = dir.file("typo.toml"), wrong = dir.file("wrong.toml");
  std::ofstream(typo) << "baudrate = 9600\n";
  std::ofstream(wrong) << "parity = \"X\"\n";
  const RunResult a = run_program({homingd_path(), "--config", typo}, 20s);
  CHECK(a.code() == 2);
  CHECK(a.err.find("baudrate") != std::string::npos);
  const RunResult b = run_program({homingd_path(), "--config", wrong}, 20s);
  CHECK(b.code() == 2);
  CHECK(b.err.find("--parity") != std::string::npos);
  CHECK(b.err.find("N,E,O") != std::string::npos);
}

TEST_CASE("a fraction for a whole-number option or an empty db in the config file stops the start saying what is expected") {
  TempDir dir;
  const std::string fraction = dir.file("fraction.toml"), empty_db = dir.file("empty_db.toml");
  std::ofstream(fraction) << "db = \"" << dir.file("f.db") << "\"\nunit = 1.5\n";
  std::ofstream(empty_db) << "db = \"\"\n";
  const RunResult a = run_program({homingd_path(), "--config", fraction}, 20s);
  INFO(a.err);
  CHECK(a.code() == 2);
  CHECK(a.err.find("--unit: expected a whole number from 1 to 247, got '1.5'") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir.file("f.db")));
  // The value checked is the value used: "0100" is octal to CLI11 (64), below --period-us's 100.
  const RunResult octal = run_program({homingd_path(), "--db", dir.file("o.db"), "--period-us", "0100"}, 20s);
  INFO(octal.err);
  CHECK(octal.code() == 2);
  CHECK(octal.err.find("--period-us") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir.file("o.db")));
  const RunResult b = run_program({homingd_path(), "--config", empty_db}, 20s);
  INFO(b.err);
  CHECK(b.code() == 2);
  CHECK(b.err.find("--db") != std::string::npos);
  CHECK(b.err.find("empty path") != std::string::npos);
  CHECK(b.err.find("WAL") == std::string::npos);
}

TEST_CASE("import_settings and export_settings in the config file stop the start: they are one-shot actions") {
  TempDir dir;
  const std::string settings = dir.file("base.toml"), config = dir.file("service.toml");
  std::ofstream(settings) << "format = \"homing-module-settings\"\nformat_version = 2\n[settings]\naxis.x.pull_off = 2.5\n";
  std::ofstream(config) << "db = \"" << dir.file("z.db") << "\"\nimport_settings = \"" << settings << "\"\n";
  const RunResult r = run_program({homingd_path(), "--config", config}, 20s);
  CHECK(r.code() == 2);
  CHECK(r.err.find("import_settings") != std::string::npos);
  CHECK(r.err.find("one-shot action") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir.file("z.db")));  // nothing applied
}
