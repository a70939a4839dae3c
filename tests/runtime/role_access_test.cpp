// Roles of Modbus/TCP Security clients on the real request path
// (ModbusService + ControlLoop stepped by hand, no sockets): what each access
// level may write, that a refused write is exception 01 and changes nothing,
// and the one table of roles.
#include <catch2/catch.hpp>

#include <memory>

#include "homing/sim/simulator_io.hpp"
#include "registers/defaults.hpp"
#include "registers/lookup.hpp"
#include "registers/sim_bindings.hpp"
#include "server/client_role.hpp"
#include "server/control_loop.hpp"
#include "server/modbus_service.hpp"

namespace {

using server::Access;

struct Service {
  std::unique_ptr<server::ControlLoop> loop;
  std::unique_ptr<server::ModbusService> service;

  Service() {
    const auto settings = registers::default_settings();
    loop = std::make_unique<server::ControlLoop>(
        settings, std::make_unique<homing::sim::SimulatorIo>(registers::default_sim_config()), 1000, 1.0);
    service = std::make_unique<server::ModbusService>(server::ServiceConfig{}, *loop, nullptr, settings);
  }

  // FC 6 (holding) or FC 5 (coil) to a named register; the reply PDU.
  std::vector<std::uint8_t> write(Access access, std::string_view name, std::uint16_t value) {
    const auto* r = registers::find_register(name);
    REQUIRE(r);
    server::ClientInfo client(3, server::Transport::tls, "127.0.0.1:40000");
    client.access = access;
    client.identity = "CN=test (role test)";
    const bool coil = r->table == registers::Table::coil;
    const std::uint16_t v = coil ? (value ? 0xFF00 : 0) : value;
    const std::vector<std::uint8_t> pdu{static_cast<std::uint8_t>(coil ? 5 : 6), static_cast<std::uint8_t>(r->address >> 8),
                                        static_cast<std::uint8_t>(r->address), static_cast<std::uint8_t>(v >> 8),
                                        static_cast<std::uint8_t>(v)};
    const std::uint8_t unit = r->unit == registers::Unit::module ? 1 : 247;
    return service->handle(unit, pdu, client).pdu;
  }
  bool accepted(Access access, std::string_view name, std::uint16_t value) {
    const auto reply = write(access, name, value);
    return !reply.empty() && (reply[0] & 0x80) == 0;
  }
  bool refused_01(Access access, std::string_view name, std::uint16_t value) {
    const auto reply = write(access, name, value);
    return reply.size() == 2 && (reply[0] & 0x80) && reply[1] == 1;
  }
};

}  // namespace

TEST_CASE("the role table names viewer, operator and engineer, and nothing else") {
  CHECK(server::access_of_role("viewer") == Access::read_only);
  CHECK(server::access_of_role("operator") == Access::commands);
  CHECK(server::access_of_role("engineer") == Access::settings);
  CHECK_FALSE(server::access_of_role("admin"));
  CHECK_FALSE(server::access_of_role("Engineer"));
  CHECK_FALSE(server::access_of_role(""));
}

TEST_CASE("commands, heartbeat, move targets and the permit need commands, the rest of the writes settings") {
  using registers::Table;
  using registers::Unit;
  const auto needed = [](std::string_view name) {
    const auto* r = registers::find_register(name);
    REQUIRE(r);
    return server::access_needed(r->unit, r->table, r->address, r->words());
  };
  for (const char* name : {"cmd.home_all", "cmd.home_axes", "cmd.abort", "cmd.reset_alarm", "cmd.home.x", "cmd.jog_plus.y",
                           "cmd.jog_minus.z", "cmd.move.a", "axis.a.target", "host.heartbeat", "host.homing_permit"})
    CHECK(needed(name) == Access::commands);
  for (const char* name : {"axis.x.seek_feedrate", "global.watchdog_ms", "sequence.step1", "security.unlock",
                           "cmd.lock_settings", "sim.seed", "sim.x.sensor_max", "sim.estop"})
    CHECK(needed(name) == Access::settings);
  // A range holding a command and a setting needs the higher of the two.
  const auto* heartbeat = registers::find_register("host.heartbeat");
  CHECK(server::access_needed(Unit::module, Table::holding_register, 0, heartbeat->address + 1) == Access::settings);
}

TEST_CASE("a viewer's write, even a command, is exception 01 and changes nothing") {
  Service s;
  CHECK(s.refused_01(Access::read_only, "host.heartbeat", 9));
  CHECK(s.refused_01(Access::read_only, "cmd.home_all", 1));
  CHECK(s.refused_01(Access::read_only, "axis.x.seek_feedrate", 1200));
  CHECK(s.service->settings().axes[0].seek_feedrate_mm_per_min == 1000);
  s.loop->run_period(0.001);
  CHECK_FALSE(s.loop->snapshot().status.homing);
}

TEST_CASE("an operator commands the machine but its settings and simulator writes are exception 01") {
  Service s;
  CHECK(s.accepted(Access::commands, "host.heartbeat", 9));
  CHECK(s.accepted(Access::commands, "host.homing_permit", 1));
  CHECK(s.refused_01(Access::commands, "axis.x.seek_feedrate", 1200));
  CHECK(s.refused_01(Access::commands, "security.unlock", 1));
  CHECK(s.refused_01(Access::commands, "cmd.lock_settings", 1));
  CHECK(s.refused_01(Access::commands, "sim.estop", 1));
  CHECK(s.service->settings().axes[0].seek_feedrate_mm_per_min == 1000);
  CHECK(s.accepted(Access::commands, "cmd.home_all", 1));
  for (int i = 0; i < 5; ++i) s.loop->run_period(0.001);
  CHECK(s.loop->snapshot().status.homing);
}

TEST_CASE("an operator homes chosen axes with cmd.home_axes, as homingctl home x does") {
  Service s;
  CHECK(s.accepted(Access::commands, "cmd.home_axes", 0b1));
  for (int i = 0; i < 5; ++i) s.loop->run_period(0.001);
  const auto st = s.loop->snapshot().status;
  CHECK(st.homing);
  CHECK(st.axes[0].busy);
  CHECK_FALSE(st.axes[1].busy);
}

TEST_CASE("an engineer writes settings and the simulator unit") {
  Service s;
  CHECK(s.accepted(Access::settings, "axis.x.seek_feedrate", 1200));
  CHECK(s.service->settings().axes[0].seek_feedrate_mm_per_min == 1200);
  CHECK(s.accepted(Access::settings, "cmd.home_all", 1));
}
