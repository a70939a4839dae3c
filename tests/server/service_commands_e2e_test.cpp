// Service commands over Modbus/TCP on the real homingd (simulator): cmd.unhome.<a>
// forgets an axis's reference without moving it, logged with the client; with
// global.single_axis_homing = 0 a single-axis home is refused with its own
// command result and only home-all homes.
#include <catch2/catch.hpp>
#include <sqlite3.h>

#include <string>
#include <vector>

#include "daemon.hpp"
#include "homing/status.hpp"
#include "tests/support/temp_dir.hpp"

using namespace e2e;

namespace {
template <class E>
std::int64_t v(E e) {
  return static_cast<std::int64_t>(e);
}
bool homed_all(Client& c) { return c.read("status.state") == v(homing::MachineState::homed); }

// The audit rows of one register name in a homingd database, read with
// SQLite itself: "old -> new by transport client".
std::vector<std::string> audit_rows(const std::string& db, const std::string& name) {
  std::vector<std::string> out;
  sqlite3* h = nullptr;
  REQUIRE(sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  REQUIRE(sqlite3_prepare_v2(h, "SELECT old_value, new_value, transport, client FROM audit WHERE name = ? ORDER BY id",
                             -1, &st, nullptr) == SQLITE_OK);
  sqlite3_bind_text(st, 1, name.c_str(), -1, SQLITE_TRANSIENT);
  while (sqlite3_step(st) == SQLITE_ROW)
    out.push_back(std::to_string(sqlite3_column_int64(st, 0)) + " -> " + std::to_string(sqlite3_column_int64(st, 1)) +
                  " by " + reinterpret_cast<const char*>(sqlite3_column_text(st, 2)) + " " +
                  reinterpret_cast<const char*>(sqlite3_column_text(st, 3)));
  sqlite3_finalize(st);
  sqlite3_close(h);
  return out;
}
}  // namespace

TEST_CASE("over Modbus: cmd.unhome.<a> unhomes the axis without moving it and the log names the client") {
  Daemon d;
  Client c = Client::tcp(d.port());
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return homed_all(c) || c.read("status.alarm") != 0; }, 30s));
  REQUIRE(c.read("axis.x.homed") == 1);
  const std::int64_t x_at = c.read("sim.x.actual_position");
  const std::int64_t count = c.read("status.command_count");
  REQUIRE(c.write("cmd.unhome.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") != count; }, 2s));
  CHECK(c.read("status.last_command_result") == v(homing::CommandResult::accepted));
  CHECK(c.read("axis.x.homed") == 0);
  CHECK(c.read("axis.y.homed") == 1);
  CHECK(c.read("sim.x.actual_position") == x_at);
  CHECK(c.read("cmd.unhome.x") == 0);
  CHECK(d.log().find("unhome.x") != std::string::npos);
}

TEST_CASE("over Modbus: with global.single_axis_homing 0 a single-axis home is refused_home_all_only and home-all homes") {
  Daemon d;
  Client c = Client::tcp(d.port());
  CHECK(c.read("global.single_axis_homing") == 1);
  c.set("global.single_axis_homing", 0);
  const std::int64_t x_at = c.read("sim.x.actual_position");
  std::int64_t count = c.read("status.command_count");
  REQUIRE(c.write("cmd.home.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") != count; }, 2s));
  CHECK(c.read("status.last_command_result") == v(homing::CommandResult::refused_home_all_only));
  count = c.read("status.command_count");
  REQUIRE(c.write("cmd.home_axes", 0b011) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") != count; }, 2s));
  CHECK(c.read("status.last_command_result") == v(homing::CommandResult::refused_home_all_only));
  CHECK(c.read("status.homing") == 0);
  CHECK(c.read("sim.x.actual_position") == x_at);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return homed_all(c) || c.read("status.alarm") != 0; }, 30s));
  CHECK(homed_all(c));
}

TEST_CASE("over Modbus: cmd.set_position.<a> gives an unhomed axis axis.<a>.target where it stands, audited with the "
          "client, and is refused_homed once it is homed") {
  test_support::TempDir dir;
  const std::string db = dir.file("machine.db");
  {
    Daemon d({.db = db});
    Client c = Client::tcp(d.port());
    const std::int64_t x_at = c.read("sim.x.actual_position");
    const std::int64_t before = c.read("axis.x.position");
    REQUIRE(c.write("axis.x.target", 12'345) == 0);  // 12.345 mm
    std::int64_t count = c.read("status.command_count");
    REQUIRE(c.write("cmd.set_position.x", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("status.command_count") != count; }, 2s));
    CHECK(c.read("status.last_command_result") == v(homing::CommandResult::accepted));
    CHECK(c.read("axis.x.position") == 12'345);
    CHECK(c.read("axis.x.homed") == 0);
    CHECK(c.read("sim.x.actual_position") == x_at);  // nothing moved
    CHECK(c.read("cmd.set_position.x") == 0);
    REQUIRE(wait_until([&] { return d.log().find("X set by hand from") != std::string::npos; }, 2s));
    const auto rows = audit_rows(db, "axis.x.position");
    REQUIRE(rows.size() == 1);
    CHECK(rows[0].starts_with(std::to_string(before) + " -> 12345 by tcp 127.0.0.1:"));
    // Homed, the reference is never overwritten by hand.
    REQUIRE(c.write("cmd.home_all", 1) == 0);
    REQUIRE(wait_until([&] { return homed_all(c) || c.read("status.alarm") != 0; }, 30s));
    REQUIRE(c.read("axis.x.homed") == 1);
    const std::int64_t homed_at = c.read("axis.x.position");
    count = c.read("status.command_count");
    REQUIRE(c.write("cmd.set_position.x", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("status.command_count") != count; }, 2s));
    CHECK(c.read("status.last_command_result") == v(homing::CommandResult::refused_homed));
    CHECK(c.read("axis.x.position") == homed_at);
  }
  CHECK(audit_rows(db, "axis.x.position").size() == 1);  // the refused one left no row
}
