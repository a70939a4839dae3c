// Edit sessions as an HMI that writes one tag per request meets them
// (docs/hmi-integration.md "Edit sessions"): begin, stage settings in any
// order, commit all or nothing; a combination refused at the commit changes
// nothing and names the rule; discard; the timeout; two clients; over RTU.
#include <catch2/catch.hpp>

#include <thread>
#include <vector>

#include "daemon.hpp"
#include "registers/errors.hpp"

using namespace e2e;
using registers::RefusalReason;

namespace {

constexpr std::int64_t kBegin = 1, kCommit = 2, kDiscard = 3;
constexpr std::int64_t kNone = 0, kOpen = 1, kExpired = 2;

std::int64_t code(RefusalReason r) { return static_cast<std::int64_t>(r); }
std::int64_t code(homing::CheckRule r) { return registers::kRuleReasonBase + static_cast<std::int64_t>(r); }

int fc16(Client& c, std::uint16_t address, const std::vector<std::uint16_t>& words) {
  if (modbus_write_registers(c.ctx(), address, static_cast<int>(words.size()), words.data()) >= 0) return 0;
  return exception_of(errno) ? exception_of(errno) : -1;
}

}  // namespace

TEST_CASE("an edit session stages settings in the order an HMI writes them and the commit applies them together") {
  Daemon d;
  Client c = Client::tcp(d.port());
  // Default X: acceleration 500 mm/s², max stop distance 10 mm: 12000 mm/min
  // (200 mm/s) needs 40 mm to stop, so alone the feedrate is refused.
  REQUIRE(c.read("axis.x.acceleration") == 500);
  CHECK(c.write("axis.x.seek_feedrate", 12000) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);

  REQUIRE(c.write("edit.command", kBegin) == 0);
  CHECK(c.read("edit.state") == kOpen);
  CHECK(c.write("axis.x.seek_feedrate", 12000) == 0);  // staged, not judged alone
  CHECK(c.write("axis.x.acceleration", 5000) == 0);
  CHECK(c.read("edit.staged") == 2);
  // Staged, not applied: reads show the settings in force.
  CHECK(c.read("axis.x.seek_feedrate") == 1000);
  CHECK(c.read("axis.x.acceleration") == 500);
  // A value out of its range is refused at once, as without a session.
  CHECK(c.write("axis.x.acceleration", 65000) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);

  REQUIRE(c.write("edit.command", kCommit) == 0);
  CHECK(c.read("edit.state") == kNone);
  CHECK(c.read("axis.x.seek_feedrate") == 12000);
  CHECK(c.read("axis.x.acceleration") == 5000);
  const std::string log = d.log();
  CHECK(log.find("edit session of tcp 127.0.0.1:") != std::string::npos);
  CHECK(log.find("committed: 2 staged settings, 2 changed") != std::string::npos);
  // Back to one write at a time: applied at once.
  CHECK(c.write("axis.x.pull_off", um(2)) == 0);
  CHECK(c.read("axis.x.pull_off") == um(2));
}

TEST_CASE("a combination refused at the commit applies none of the session and names the rule and the register") {
  Daemon d;
  Client c = Client::tcp(d.port());
  REQUIRE(c.write("edit.command", kBegin) == 0);
  CHECK(c.write("axis.x.pull_off", um(2)) == 0);          // fine on its own
  CHECK(c.write("axis.x.latch_feedrate", 1000) == 0);     // as fast as the seek: the rule refuses it
  CHECK(c.write("edit.command", kCommit) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.read("axis.x.pull_off") == um(1));  // nothing of it applied
  CHECK(c.read("axis.x.latch_feedrate") == 100);
  CHECK(c.read("status.last_refusal_reason") == code(homing::CheckRule::latch_not_slower));
  CHECK(c.read("status.last_refused_register") == registers::find_register("axis.x.latch_feedrate")->address);
  CHECK(c.read("status.last_refused_write") == registers::find_register("edit.command")->address);
  // The session stays open with what it staged: fix the one tag, commit again.
  CHECK(c.read("edit.state") == kOpen);
  CHECK(c.write("axis.x.latch_feedrate", 50) == 0);
  REQUIRE(c.write("edit.command", kCommit) == 0);
  CHECK(c.read("axis.x.pull_off") == um(2));
  CHECK(c.read("axis.x.latch_feedrate") == 50);
}

TEST_CASE("a discarded edit session changes nothing, and begin, commit and discard out of turn are refused") {
  Daemon d;
  Client c = Client::tcp(d.port());
  CHECK(c.write("edit.command", kCommit) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.read("status.last_refusal_reason") == code(RefusalReason::edit_no_session));
  CHECK(c.write("edit.command", kDiscard) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  REQUIRE(c.write("edit.command", kBegin) == 0);
  CHECK(c.write("edit.command", kBegin) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  CHECK(c.read("status.last_refusal_reason") == code(RefusalReason::edit_session_open));
  CHECK(c.write("axis.y.home_position", um(3)) == 0);
  // A request that mixes a setting with a command is refused whole.
  const auto& home_axes = *registers::find_register("cmd.home_axes");
  CHECK(fc16(c, home_axes.address, {1, 5}) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);  // cmd.home_axes + global.trend_cycles
  CHECK(c.read("status.last_refusal_reason") == code(RefusalReason::edit_mixed));
  CHECK(c.read("edit.staged") == 1);
  REQUIRE(c.write("edit.command", kDiscard) == 0);
  CHECK(c.read("edit.state") == kNone);
  CHECK(c.read("axis.y.home_position") == 0);
  CHECK(d.log().find("discarded by its client (1 staged settings dropped)") != std::string::npos);
}

TEST_CASE("an edit session left past global.edit_timeout_s is discarded and logged, and its writes are refused until begin or discard") {
  Daemon d;
  Client c = Client::tcp(d.port());
  REQUIRE(c.write("global.edit_timeout_s", 5) == 0);
  REQUIRE(c.write("edit.command", kBegin) == 0);
  CHECK(c.write("axis.x.pull_off", um(2)) == 0);
  const auto deadline = Clock::now() + 15s;
  while (c.read("edit.state") != kExpired && Clock::now() < deadline) std::this_thread::sleep_for(200ms);
  REQUIRE(c.read("edit.state") == kExpired);
  CHECK(d.log().find("discarded: no write or commit for 5 s (global.edit_timeout_s); its 1 staged settings") !=
        std::string::npos);
  // The HMI still believes it stages: its writes are refused, never applied one by one.
  CHECK(c.write("axis.x.pull_off", um(2.5)) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_FAILURE);
  CHECK(c.read("status.last_refusal_reason") == code(RefusalReason::edit_session_expired));
  CHECK(c.write("edit.command", kCommit) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_FAILURE);
  CHECK(c.read("axis.x.pull_off") == um(1));
  REQUIRE(c.write("edit.command", kDiscard) == 0);
  CHECK(c.read("edit.state") == kNone);
  CHECK(c.write("axis.x.pull_off", um(2.5)) == 0);
  CHECK(c.read("axis.x.pull_off") == um(2.5));
}

TEST_CASE("two clients: one's edit session stages only its own writes, the other's apply at once, and a closed connection discards its session") {
  Daemon d;
  Client hmi = Client::tcp(d.port());
  Client plc = Client::tcp(d.port());
  REQUIRE(hmi.write("edit.command", kBegin) == 0);
  CHECK(hmi.write("axis.x.pull_off", um(2)) == 0);
  CHECK(plc.read("edit.state") == kNone);  // the session is the HMI connection's
  CHECK(plc.write("axis.y.pull_off", um(3)) == 0);
  CHECK(plc.read("axis.y.pull_off") == um(3));  // applied at once
  CHECK(hmi.read("axis.y.pull_off") == um(3));
  CHECK(plc.read("axis.x.pull_off") == um(1));  // the HMI's is still staged
  REQUIRE(hmi.write("edit.command", kCommit) == 0);
  CHECK(plc.read("axis.x.pull_off") == um(2));

  // A session whose connection closes is discarded, as a transaction is.
  {
    Client gone = Client::tcp(d.port());
    REQUIRE(gone.write("edit.command", kBegin) == 0);
    CHECK(gone.write("axis.z.pull_off", um(4)) == 0);
  }
  const auto deadline = Clock::now() + 5s;
  while (d.log().find("discarded: the connection closed before its commit") == std::string::npos &&
         Clock::now() < deadline)
    std::this_thread::sleep_for(50ms);
  CHECK(d.log().find("discarded: the connection closed before its commit (1 staged settings not applied)") !=
        std::string::npos);
  CHECK(plc.read("axis.z.pull_off") == um(1));
}

TEST_CASE("over RTU an edit session stages and commits on the serial line while a TCP client reads the settings in force") {
  PtyPair pty;
  Daemon d(DaemonOptions{.time_scale = 10, .extra = {"--rtu", pty.server_end(), "--baud", "19200", "--parity", "E"}});
  Client rtu = Client::rtu(pty.client_end(), 19200, 'E');
  Client tcp = Client::tcp(d.port());
  REQUIRE(rtu.write("edit.command", kBegin) == 0);
  CHECK(rtu.write("axis.x.seek_feedrate", 12000) == 0);
  CHECK(rtu.write("axis.x.acceleration", 5000) == 0);
  CHECK(tcp.read("axis.x.seek_feedrate") == 1000);
  CHECK(rtu.read("edit.staged") == 2);
  REQUIRE(rtu.write("edit.command", kCommit) == 0);
  CHECK(tcp.read("axis.x.seek_feedrate") == 12000);
  CHECK(tcp.read("axis.x.acceleration") == 5000);
}
