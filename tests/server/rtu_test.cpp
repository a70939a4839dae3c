// Modbus RTU over a pseudo-terminal pair (socat): homingd serves one end, a
// libmodbus RTU client the other. RTU serves the module unit only, so the
// simulator's truth is read over TCP at the same time.
#include <catch2/catch.hpp>

#include "daemon.hpp"
#include "homing/phases.hpp"
#include "homing/status.hpp"

using namespace e2e;

namespace {

struct RtuRig {
  PtyPair pty;
  Daemon daemon;
  Client rtu;
  Client tcp;
  explicit RtuRig(std::vector<std::string> more = {})
      : daemon(DaemonOptions{.time_scale = 10, .extra = [&] {
                               std::vector<std::string> extra{"--rtu", pty.server_end(), "--baud", "19200", "--parity", "E"};
                               extra.insert(extra.end(), more.begin(), more.end());
                               return extra;
                             }()}),
        rtu(Client::rtu(pty.client_end(), 19200, 'E')),
        tcp(Client::tcp(daemon.port())) {}
};

// The Modbus RTU CRC (polynomial 0xA001, low byte first on the wire), written
// out here so that the frame does not depend on the code under test.
std::vector<std::uint8_t> with_crc(std::vector<std::uint8_t> frame) {
  std::uint16_t crc = 0xFFFF;
  for (const std::uint8_t b : frame) {
    crc ^= b;
    for (int i = 0; i < 8; ++i) crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001) : crc >> 1;
  }
  frame.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  frame.push_back(static_cast<std::uint8_t>(crc >> 8));
  return frame;
}

}  // namespace

TEST_CASE("RTU: a write of 124 registers, a frame longer than the standard's 256 bytes, is answered with exception 03 "
          "and changes nothing") {
  RtuRig rig;
  Client& rtu = rig.rtu;
  REQUIRE(rtu.read("status.map_version") == registers::kMapVersion);
  const auto& pull = reg("axis.x.pull_off");
  std::vector<std::uint8_t> body{1, 0x10, static_cast<std::uint8_t>(pull.address >> 8),
                                 static_cast<std::uint8_t>(pull.address & 0xFF), 0, 124, 248};
  body.resize(7 + 248, 0x01);
  const auto frame = with_crc(body);
  REQUIRE(frame.size() == 257);
  const int fd = modbus_get_socket(rtu.ctx());
  REQUIRE(::write(fd, frame.data(), frame.size()) == static_cast<ssize_t>(frame.size()));
  std::uint8_t rsp[MODBUS_RTU_MAX_ADU_LENGTH];
  const int n = modbus_receive_confirmation(rtu.ctx(), rsp);
  REQUIRE(n == 5);
  CHECK(rsp[0] == 1);
  CHECK(rsp[1] == 0x90);
  CHECK(rsp[2] == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(rtu.read("axis.x.pull_off") == pull.default_raw);
  CHECK(rig.tcp.read("axis.x.pull_off") == pull.default_raw);
}

TEST_CASE("RTU: configure and home all over a serial line, checked against the simulator over TCP") {
  RtuRig rig;
  INFO(rig.daemon.listening_line());
  CHECK(rig.daemon.listening_line().find("rtu") != std::string::npos);
  Client& rtu = rig.rtu;
  Client& tcp = rig.tcp;
  REQUIRE(rtu.read("status.map_version") == registers::kMapVersion);

  // Configure over RTU; TCP sees it (one module behind both transports).
  rtu.set("axis.x.pull_off", um(2.0));
  rtu.set("axis.y.home_position", um(3.25));
  rtu.set("axis.z.seek_feedrate", 1200);
  CHECK(rtu.read("axis.x.pull_off") == 2000);
  CHECK(tcp.read("axis.x.pull_off") == 2000);
  CHECK(tcp.read("axis.y.home_position") == 3250);
  CHECK(tcp.read("axis.z.seek_feedrate") == 1200);

  REQUIRE(rtu.write("cmd.home_all", 1) == 0);
  bool saw_z_seek = false, saw_xy_seek = false, saw_sim_move = false;
  const auto z_start = tcp.read("sim.z.actual_position");
  const auto deadline = Clock::now() + 20s;
  int state = 0;
  while (Clock::now() < deadline) {
    state = static_cast<int>(rtu.read("status.state"));
    // Z read before and after X and Y: the reads are not one snapshot.
    const auto z1 = rtu.read("axis.z.phase");
    const auto x = rtu.read("axis.x.phase"), y = rtu.read("axis.y.phase");
    const auto z2 = rtu.read("axis.z.phase");
    const int seek = static_cast<int>(homing::Phase::seek);
    if (z1 == seek && z2 == seek) {
      saw_z_seek = true;
      CHECK(x == static_cast<int>(homing::Phase::waiting));
      CHECK(y == static_cast<int>(homing::Phase::waiting));
    }
    if (x == seek || y == seek) {
      saw_xy_seek = true;
      CHECK(z2 == static_cast<int>(homing::Phase::done));
    }
    if (tcp.read("sim.z.actual_position") != z_start) saw_sim_move = true;
    if (state == static_cast<int>(homing::MachineState::homed) || state == static_cast<int>(homing::MachineState::alarm))
      break;
  }
  REQUIRE(state == static_cast<int>(homing::MachineState::homed));
  CHECK(saw_z_seek);
  CHECK(saw_xy_seek);
  CHECK(saw_sim_move);
  for (const char* a : {"x", "y", "z"}) {
    const std::string p = std::string("axis.") + a + ".";
    const std::string s = std::string("sim.") + a + ".";
    INFO("axis " << a);
    CHECK(rtu.read(p + "homed") == 1);
    CHECK(rtu.read(p + "position") == rtu.read(p + "home_position"));
    const double expected = tcp.read_mm(s + "sensor_max") + tcp.read_mm(s + "hysteresis") + rtu.read_mm(p + "pull_off");
    CHECK(tcp.read_mm(s + "actual_position") == Approx(expected).margin(0.02));
  }
  CHECK(rtu.read("axis.y.position") == 3250);
}

TEST_CASE("RTU: a broadcast write is applied and never answered, other units are silent, bad frames are survived") {
  RtuRig rig;
  Client& rtu = rig.rtu;
  Client& tcp = rig.tcp;
  REQUIRE(rtu.read("status.map_version") == registers::kMapVersion);
  rtu.set_timeout(300ms);

  // FC 6 to unit 0.
  const auto& jog = reg("axis.x.jog_feedrate");
  std::vector<std::uint8_t> req{0, 0x06, static_cast<std::uint8_t>(jog.address >> 8),
                                static_cast<std::uint8_t>(jog.address & 0xFF), 0x04, 0xD2};  // 1234
  REQUIRE(modbus_send_raw_request(rtu.ctx(), req.data(), static_cast<int>(req.size())) > 0);
  std::uint8_t rsp[MODBUS_RTU_MAX_ADU_LENGTH];
  CHECK(modbus_receive_confirmation(rtu.ctx(), rsp) == -1);  // nothing came back
  CHECK(errno == ETIMEDOUT);
  REQUIRE(wait_until([&] { return tcp.read("axis.x.jog_feedrate") == 1234; }, 2s));
  CHECK(rtu.read("axis.x.jog_feedrate") == 1234);

  // FC 16 of a 32-bit value to unit 0.
  const auto& pull = reg("axis.y.pull_off");
  std::vector<std::uint8_t> req16{0, 0x10, static_cast<std::uint8_t>(pull.address >> 8),
                                  static_cast<std::uint8_t>(pull.address & 0xFF), 0, 2, 4, 0, 0, 0x0B, 0xB8};  // 3000
  REQUIRE(modbus_send_raw_request(rtu.ctx(), req16.data(), static_cast<int>(req16.size())) > 0);
  CHECK(modbus_receive_confirmation(rtu.ctx(), rsp) == -1);
  REQUIRE(wait_until([&] { return tcp.read("axis.y.pull_off") == 3000; }, 2s));

  // A broadcast refused by validation is not applied and not answered either.
  std::vector<std::uint8_t> bad{0, 0x06, static_cast<std::uint8_t>(jog.address >> 8),
                                static_cast<std::uint8_t>(jog.address & 0xFF), 0, 0};  // 0 is out of range
  REQUIRE(modbus_send_raw_request(rtu.ctx(), bad.data(), static_cast<int>(bad.size())) > 0);
  CHECK(modbus_receive_confirmation(rtu.ctx(), rsp) == -1);
  CHECK(tcp.read("axis.x.jog_feedrate") == 1234);

  // The simulator unit and unknown units are not served over RTU: silence.
  for (int unit : {247, 5}) {
    INFO("unit " << unit);
    rtu.use_unit(unit);
    std::uint16_t w[2];
    CHECK(modbus_read_registers(rtu.ctx(), 0, 1, w) == -1);
    CHECK(errno == ETIMEDOUT);
  }
  rtu.use_unit(1);

  // Garbage on the line (a frame with a bad CRC, then noise): the server counts it and goes on.
  const int fd = modbus_get_socket(rtu.ctx());
  const std::uint8_t garbage[] = {0x01, 0x03, 0x00, 0x00, 0x00, 0x01, 0xDE, 0xAD, 0x55, 0xAA, 0x00, 0xFF};
  REQUIRE(::write(fd, garbage, sizeof(garbage)) == static_cast<ssize_t>(sizeof(garbage)));
  std::this_thread::sleep_for(400ms);
  modbus_flush(rtu.ctx());
  rtu.set_timeout(1000ms);
  bool answered = wait_until([&] { return rtu.try_read("status.map_version") == registers::kMapVersion; }, 3s, 50ms);
  CHECK(answered);
  // An exception over RTU, with nothing changed.
  std::uint16_t w = 0;
  CHECK(modbus_write_register(rtu.ctx(), reg("axis.x.pull_off").address, 1) == -1);
  CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  CHECK(modbus_read_registers(rtu.ctx(), 9000, 1, &w) == -1);
  CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  CHECK(tcp.read("axis.x.pull_off") == reg("axis.x.pull_off").default_raw);
  // homingd is still whole on both transports.
  CHECK(rtu.read("axis.y.pull_off") == 3000);
  CHECK(tcp.read("status.map_version") == registers::kMapVersion);
  const auto st = rig.daemon.stop(SIGTERM);
  REQUIRE(st);
  CHECK(WIFEXITED(*st));
}

TEST_CASE("RTU: a jog held by a master that goes silent stops after --rtu-jog-release-ms and its coil reads 0") {
  RtuRig rig({"--rtu-jog-release-ms", "400"});
  Client& rtu = rig.rtu;
  Client& tcp = rig.tcp;
  rtu.set("axis.x.jog_feedrate", 100);  // slow: the carriage stays well inside its travel
  REQUIRE(rtu.write("cmd.jog_plus.x", 1) == 0);
  const double start = tcp.read_mm("sim.x.actual_position");
  // A master that keeps polling (here every 100 ms, three times the release
  // time in all) keeps its jog: silence is what releases it, not time.
  for (int i = 0; i < 12; ++i) {
    std::this_thread::sleep_for(100ms);
    REQUIRE(rtu.read("cmd.jog_plus.x") == 1);
  }
  CHECK(tcp.read("cmd.jog_plus.x") == 1);
  CHECK(tcp.read("axis.x.velocity") != 0);
  CHECK(tcp.read_mm("sim.x.actual_position") > start);
  // The panel dies: nothing more on the line. The daemon is watched over TCP only.
  const auto silent_from = Clock::now();
  REQUIRE(wait_until([&] { return tcp.read("cmd.jog_plus.x") == 0; }, 5s));
  CHECK(Clock::now() - silent_from >= 350ms);
  REQUIRE(wait_until([&] { return tcp.read("axis.x.velocity") == 0; }, 5s));
  const double stopped = tcp.read_mm("sim.x.actual_position");
  std::this_thread::sleep_for(300ms);
  CHECK(tcp.read_mm("sim.x.actual_position") == stopped);
  CHECK(rig.daemon.log().find("no request from the master for") != std::string::npos);
  // The master talks again: nothing restarts by itself; a new press jogs.
  CHECK(rtu.read("cmd.jog_plus.x") == 0);
  REQUIRE(rtu.write("cmd.jog_plus.x", 1) == 0);
  REQUIRE(wait_until([&] { return tcp.read("axis.x.velocity") != 0; }, 5s));
  REQUIRE(rtu.write("cmd.jog_plus.x", 0) == 0);
}

TEST_CASE("RTU: with --rtu-jog-release-ms 0 a silent master's jog runs on until its coil is written 0") {
  RtuRig rig({"--rtu-jog-release-ms", "0"});
  Client& rtu = rig.rtu;
  Client& tcp = rig.tcp;
  rtu.set("axis.x.jog_feedrate", 100);
  REQUIRE(rtu.write("cmd.jog_plus.x", 1) == 0);
  std::this_thread::sleep_for(1500ms);  // the default release (1000 ms) would have stopped it
  CHECK(tcp.read("cmd.jog_plus.x") == 1);
  CHECK(tcp.read("axis.x.velocity") != 0);
  REQUIRE(rtu.write("cmd.jog_plus.x", 0) == 0);
  REQUIRE(wait_until([&] { return tcp.read("axis.x.velocity") == 0; }, 5s));
  CHECK(rig.daemon.log().find("no request from the master for") == std::string::npos);
}
