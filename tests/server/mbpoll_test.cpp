// mbpoll, an independent Modbus master, against the real homingd: settings
// written and read (32-bit big-endian word order, as the map says), a
// home-all started and watched, and exceptions reported. It must be installed
// (tools/install-deps.sh): a missing mbpoll fails, never skips.
#include <catch2/catch.hpp>

#include <map>
#include <regex>

#include "daemon.hpp"
#include "homing/modes.hpp"
#include "homing/status.hpp"

using namespace e2e;

namespace {

// mbpoll over TCP, 0-based addresses, one poll only.
RunResult mbpoll(int port, const std::string& type, int address, std::vector<std::string> extra = {}) {
  std::vector<std::string> argv{"mbpoll", "-m", "tcp", "-p", std::to_string(port), "-a", "1", "-0", "-1",
                                "-o",     "1", "-t", type, "-r", std::to_string(address)};
  if (type.find(":int") != std::string::npos) argv.push_back("-B");  // high word first
  argv.push_back("127.0.0.1");
  argv.insert(argv.end(), extra.begin(), extra.end());
  return run_program(argv, 10s);
}

// The values mbpoll printed: "[address]: \tvalue" lines.
std::map<int, long long> values_of(const RunResult& r) {
  std::map<int, long long> out;
  static const std::regex line(R"(\[(\d+)\]:\s+(-?\d+))");
  for (auto it = std::sregex_iterator(r.out.begin(), r.out.end(), line); it != std::sregex_iterator(); ++it)
    out[std::stoi((*it)[1])] = std::stoll((*it)[2]);
  return out;
}

long long read_one(int port, const char* name) {
  const auto& r = reg(name);
  const char* type = nullptr;
  switch (r.table) {
    case registers::Table::coil: type = "0"; break;
    case registers::Table::discrete_input: type = "1"; break;
    case registers::Table::input_register: type = r.words() == 2 ? "3:int" : "3"; break;
    case registers::Table::holding_register: type = r.words() == 2 ? "4:int" : "4"; break;
  }
  const RunResult res = mbpoll(port, type, r.address);
  INFO(name << ": " << res.out << res.err);
  REQUIRE(res.code() == 0);
  const auto v = values_of(res);
  REQUIRE(v.count(r.address) == 1);
  return v.at(r.address);
}

}  // namespace

TEST_CASE("mbpoll configures, starts and watches a home-all, exceptions reach it") {
  REQUIRE(program_exists("mbpoll"));  // tools/install-deps.sh installs it
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());

  // Reads: the map version, a block of status.
  CHECK(read_one(d.port(), "status.map_version") == registers::kMapVersion);
  const RunResult block = mbpoll(d.port(), "3", 0, {"-c", "10"});
  REQUIRE(block.code() == 0);
  CHECK(values_of(block).size() == 10);

  // Writes: a 32-bit length (FC 16 of both words, high first), a negative one, a 16-bit setting.
  REQUIRE(mbpoll(d.port(), "4:int", reg("axis.x.pull_off").address, {"2500"}).code() == 0);
  REQUIRE(mbpoll(d.port(), "4:int", reg("axis.y.home_position").address, {"--", "-7500"}).code() == 0);
  REQUIRE(mbpoll(d.port(), "4", reg("axis.z.seek_feedrate").address, {"1400"}).code() == 0);
  CHECK(c.read("axis.x.pull_off") == 2500);
  CHECK(c.read("axis.y.home_position") == -7500);
  CHECK(c.read("axis.z.seek_feedrate") == 1400);
  CHECK(read_one(d.port(), "axis.y.home_position") == -7500);

  // Exceptions: half of a 32-bit value (FC 6) is 02; an out-of-range value is 03; nothing changes.
  const RunResult half = mbpoll(d.port(), "4", reg("axis.x.pull_off").address, {"5"});
  CHECK(half.code() != 0);
  CHECK(half.err.find("Illegal data address") != std::string::npos);
  const RunResult range = mbpoll(d.port(), "4", reg("axis.x.mode").address,
                                 {std::to_string(homing::kHomingModeCount)});  // past the mode table
  CHECK(range.code() != 0);
  CHECK(range.err.find("Illegal data value") != std::string::npos);
  const RunResult unmapped = mbpoll(d.port(), "4", 9000, {"-c", "4"});
  CHECK(unmapped.err.find("Illegal data address") != std::string::npos);
  CHECK(c.read("axis.x.pull_off") == 2500);
  CHECK(c.read("axis.x.mode") == reg("axis.x.mode").default_raw);

  // A home-all from mbpoll (FC 5), watched with mbpoll until homed (bounded).
  REQUIRE(mbpoll(d.port(), "0", reg("cmd.home_all").address, {"1"}).code() == 0);
  long long state = -1;
  for (int i = 0; i < 100; ++i) {
    state = read_one(d.port(), "status.state");
    if (state == static_cast<int>(homing::MachineState::homed) ||
        state == static_cast<int>(homing::MachineState::alarm))
      break;
    std::this_thread::sleep_for(50ms);
  }
  REQUIRE(state == static_cast<int>(homing::MachineState::homed));
  CHECK(read_one(d.port(), "axis.x.homed") == 1);
  CHECK(read_one(d.port(), "axis.x.position") == 0);
  CHECK(read_one(d.port(), "axis.y.position") == -7500);
  CHECK(read_one(d.port(), "status.homing_cycles") == 1);
  // The truth: release edge (sensor_max + hysteresis) + pull-off 2.5 mm.
  const double expected = c.read_mm("sim.x.sensor_max") + c.read_mm("sim.x.hysteresis") + 2.5;
  CHECK(c.read_mm("sim.x.actual_position") == Approx(expected).margin(0.02));
}

TEST_CASE("mbpoll over RTU on a pty pair reads and writes the module unit") {
  REQUIRE(program_exists("mbpoll"));
  PtyPair pty;
  Daemon d({.time_scale = 10, .extra = {"--rtu", pty.server_end(), "--baud", "19200", "--parity", "E"}});
  Client tcp = Client::tcp(d.port());
  auto rtu_poll = [&](const std::string& type, int address, std::vector<std::string> extra) {
    std::vector<std::string> argv{"mbpoll", "-m", "rtu", "-b", "19200", "-P", "even", "-a", "1", "-0", "-1",
                                  "-o",     "1", "-t",  type,    "-r", std::to_string(address)};
    if (type.find(":int") != std::string::npos) argv.push_back("-B");
    argv.push_back(pty.client_end());
    argv.insert(argv.end(), extra.begin(), extra.end());
    return run_program(argv, 10s);
  };
  const RunResult version = rtu_poll("3", reg("status.map_version").address, {});
  INFO(version.out << version.err);
  REQUIRE(version.code() == 0);
  CHECK(values_of(version).at(reg("status.map_version").address) == registers::kMapVersion);
  REQUIRE(rtu_poll("4:int", reg("axis.z.pull_off").address, {"3300"}).code() == 0);
  CHECK(tcp.read("axis.z.pull_off") == 3300);
  const RunResult back = rtu_poll("4:int", reg("axis.z.pull_off").address, {});
  REQUIRE(back.code() == 0);
  CHECK(values_of(back).at(reg("axis.z.pull_off").address) == 3300);
}
