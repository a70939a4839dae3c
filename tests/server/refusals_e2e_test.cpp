// Why a write was refused, as a PLC programmer finds out: every refused write
// moves status.refusal_count, names its register and reason in
// status.last_refused_register / status.last_refusal_reason (read together,
// one refusal), and leaves a warn line in the daemon's log.
#include <catch2/catch.hpp>

#include "daemon.hpp"
#include "registers/errors.hpp"

using namespace e2e;
using registers::RefusalReason;

namespace {

struct LastRefusal {
  std::int64_t count = 0;
  std::int64_t address = 0;
  std::int64_t reason = 0;
};

LastRefusal last_refusal(Client& c) {
  const auto v = c.read_together({"status.refusal_count", "status.last_refused_register", "status.last_refusal_reason"});
  return {v[0], v[1], v[2]};
}

std::int64_t code(RefusalReason r) { return static_cast<std::int64_t>(r); }
std::int64_t code(homing::CheckRule r) { return registers::kRuleReasonBase + static_cast<std::int64_t>(r); }

// The refusal just made: one more than `before`, about `reg`, for `reason`,
// and logged at warn with that reason's name.
void check_refusal(Daemon& d, Client& c, const LastRefusal& before, std::string_view reg, std::int64_t reason,
                   std::string_view reason_name) {
  const LastRefusal now = last_refusal(c);
  CHECK(now.count == before.count + 1);
  CHECK(now.address == registers::find_register(reg)->address);
  CHECK(now.reason == reason);
  const std::string log = d.log();
  const std::string expected = "reason " + std::to_string(reason) + " (" + std::string(reason_name) + ") at address " +
                               std::to_string(now.address);
  INFO(log);
  CHECK(log.find(expected) != std::string::npos);
  const auto line_start = log.rfind('\n', log.find(expected));
  const std::string line = log.substr(line_start + 1, log.find('\n', log.find(expected)) - line_start - 1);
  INFO("line: " << line);
  CHECK(line.find("warn") != std::string::npos);
}

}  // namespace

TEST_CASE("every kind of refused write is counted, named by register and reason, and logged at warn") {
  Daemon d({.time_scale = 2, .extra = {"--unlock-code", "4321"}});
  Client c = Client::tcp(d.port());
  // Nothing refused yet.
  LastRefusal r = last_refusal(c);
  CHECK(r.count == 0);
  CHECK(r.reason == code(RefusalReason::none));

  SECTION("locked, wrong unlock code, then the rest once unlocked") {
    CHECK(c.write("axis.x.pull_off", um(2)) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_FAILURE);
    check_refusal(d, c, r, "axis.x.pull_off", code(RefusalReason::locked), "locked");
    r = last_refusal(c);
    CHECK(c.write("security.unlock", 1111) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
    check_refusal(d, c, r, "security.unlock", code(RefusalReason::wrong_unlock_code), "wrong_unlock_code");
    r = last_refusal(c);
    REQUIRE(c.write("security.unlock", 4321) == 0);
    CHECK(last_refusal(c).count == r.count);  // an accepted write moves nothing

    // Out of range.
    CHECK(c.write("axis.y.seek_feedrate", 65000) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
    check_refusal(d, c, r, "axis.y.seek_feedrate", code(RefusalReason::out_of_range), "out_of_range");
    r = last_refusal(c);

    // A combination rule: the latch must be slower than the seek.
    const std::int64_t seek = c.read("axis.x.seek_feedrate");
    CHECK(c.write("axis.x.latch_feedrate", seek) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
    check_refusal(d, c, r, "axis.x.latch_feedrate", code(homing::CheckRule::latch_not_slower), "latch_not_slower");
    r = last_refusal(c);

    // One half of a 32-bit value.
    const auto* pull_off = registers::find_register("axis.x.pull_off");
    CHECK(modbus_write_register(c.ctx(), pull_off->address, 0) == -1);
    CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
    check_refusal(d, c, r, "axis.x.pull_off", code(RefusalReason::split_32bit), "split_32bit");
    r = last_refusal(c);

    // An address with no register.
    int hole = -1;
    for (int a = 0; a < 1000 && hole < 0; ++a)
      if (!registers::find_register(registers::Unit::module, registers::Table::holding_register,
                                    static_cast<std::uint16_t>(a)))
        hole = a;
    REQUIRE(hole >= 0);
    CHECK(modbus_write_register(c.ctx(), hole, 1) == -1);
    CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
    const LastRefusal unmapped = last_refusal(c);
    CHECK(unmapped.count == r.count + 1);
    CHECK(unmapped.address == hole);
    CHECK(unmapped.reason == code(RefusalReason::not_mapped));
    r = unmapped;

    // Busy: a settings write while a homing cycle runs. Nothing changes.
    const std::int64_t pull_off_before = c.read("axis.z.pull_off");
    REQUIRE(c.write("cmd.home_all", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("status.homing") == 1; }, 5s));
    CHECK(c.write("axis.z.pull_off", pull_off_before + 500) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
    check_refusal(d, c, r, "axis.z.pull_off", code(RefusalReason::busy), "busy");
    CHECK(c.read("axis.z.pull_off") == pull_off_before);
    REQUIRE(c.write("cmd.abort", 1) == 0);
  }
}

TEST_CASE("a write from a client outside --write-allow is refused as client_read_only and the client can still read why") {
  Daemon d({.extra = {"--write-allow", "10.0.0.0/8"}});
  Client c = Client::tcp(d.port());
  const LastRefusal before = last_refusal(c);
  CHECK(c.write("axis.x.pull_off", um(2)) == MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  check_refusal(d, c, before, "axis.x.pull_off", code(RefusalReason::client_read_only), "client_read_only");
}

TEST_CASE("a simulator write that moves a moving carriage's cam is refused as carriage_moving naming that register") {
  Daemon d({.time_scale = 1});
  Client c = Client::tcp(d.port());
  const LastRefusal before = last_refusal(c);
  REQUIRE(c.write("cmd.jog_plus.x", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("axis.x.velocity") != 0; }, 5s));
  CHECK(c.write("sim.x.sensor_max", 5) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  REQUIRE(c.write("cmd.jog_plus.x", 0) == 0);
  check_refusal(d, c, before, "sim.x.sensor_max", code(RefusalReason::carriage_moving), "carriage_moving");
}

TEST_CASE("a combination refused about another setting names both the register written and the one to change") {
  // Y as X's software-slaved second motor: a faster seek on the master is
  // refused because the pair could no longer stop within the slave's
  // max_misalignment, the setting the refusal is about.
  Daemon d({.time_scale = 2});
  Client c = Client::tcp(d.port());
  c.set("axis.y.slave_of", 1);
  c.set("axis.y.acceleration", 100);  // the pair brakes at 100 mm/s²: 1.4 mm from 1000 mm/min, 2.3 from 1300
  const LastRefusal before = last_refusal(c);
  const std::int64_t seek = c.read("axis.x.seek_feedrate");
  CHECK(c.write("axis.x.seek_feedrate", 1300) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.read("axis.x.seek_feedrate") == seek);
  const auto v = c.read_together({"status.refusal_count", "status.last_refused_register", "status.last_refusal_reason",
                                  "status.last_refused_write"});
  CHECK(v[0] == before.count + 1);
  CHECK(v[3] == registers::find_register("axis.x.seek_feedrate")->address);
  CHECK(v[1] == registers::find_register("axis.y.max_misalignment")->address);
  CHECK(v[2] == code(homing::CheckRule::gantry_stop_too_long));
  // A refusal about the register written names it twice.
  CHECK(c.write("axis.x.latch_feedrate", seek) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  const auto w = c.read_together({"status.last_refused_register", "status.last_refused_write"});
  CHECK(w[0] == registers::find_register("axis.x.latch_feedrate")->address);
  CHECK(w[1] == w[0]);
}
