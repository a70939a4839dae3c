// One test per Modbus exception rule of the contract (shared/spec/modbus.md),
// against the real homingd over TCP with libmodbus. Every refused request is
// followed by a re-read showing that nothing changed.
#include <catch2/catch.hpp>

#include <algorithm>
#include <map>

#include "daemon.hpp"
#include "homing/modes.hpp"
#include "homing/sim/config.hpp"
#include "homing/status.hpp"

using namespace e2e;

namespace {

std::vector<std::uint8_t> pdu16(std::uint8_t unit, std::uint8_t fc, std::uint16_t a, std::uint16_t b) {
  return {unit, fc, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a & 0xFF),
          static_cast<std::uint8_t>(b >> 8), static_cast<std::uint8_t>(b & 0xFF)};
}

// FC 16 raw request: quantity and byte count as given, `data_words` words of data.
std::vector<std::uint8_t> write_multiple(std::uint8_t unit, std::uint16_t address, std::uint16_t quantity,
                                         std::uint8_t byte_count, std::size_t data_words, std::uint16_t value) {
  std::vector<std::uint8_t> r = pdu16(unit, 0x10, address, quantity);
  r.push_back(byte_count);
  for (std::size_t i = 0; i < data_words; ++i) {
    r.push_back(static_cast<std::uint8_t>(value >> 8));
    r.push_back(static_cast<std::uint8_t>(value & 0xFF));
  }
  return r;
}

// The exception code of a raw reply (unit, fc|0x80, code), or -1 if it is not one.
int exception_in(const std::vector<std::uint8_t>& reply, std::uint8_t fc) {
  if (reply.size() != 3 || reply[1] != (fc | 0x80)) return -1;
  return reply[2];
}

int fc6(Client& c, std::uint16_t address, std::uint16_t value) {
  if (modbus_write_register(c.ctx(), address, value) >= 0) return 0;
  return exception_of(errno) ? exception_of(errno) : -1;
}

int fc16(Client& c, std::uint16_t address, const std::vector<std::uint16_t>& words) {
  if (modbus_write_registers(c.ctx(), address, static_cast<int>(words.size()), words.data()) >= 0) return 0;
  return exception_of(errno) ? exception_of(errno) : -1;
}

std::vector<std::uint16_t> words_of(std::string_view name, std::int64_t raw) {
  const registers::Register& r = reg(name);
  std::vector<std::uint16_t> w(r.words());
  registers::encode_words(r, raw, registers::WordOrder::high_first, w);
  return w;
}

}  // namespace

TEST_CASE("exception 01: an unknown function code is answered at once, nothing changes") {
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto before = holding_snapshot(c);
  int answered = 0;
  for (int i = 0; i < 20; ++i) {
    // FC 7 (read exception status: libmodbus would not answer it at all), FC 0x41
    // (user-defined), FC 11 (get comm event counter), FC 8 sub-function 02
    // (return diagnostic register: the module serves 00, 01, 0A..12 only).
    for (const auto& req : std::vector<std::vector<std::uint8_t>>{
             {1, 0x07}, {1, 0x41, 0x00, 0x01}, {1, 0x0B}, {1, 0x08, 0x00, 0x02, 0x00, 0x00}}) {
      const auto reply = c.raw(req);
      INFO("FC " << int(req[1]) << ", errno " << modbus_strerror(c.last_errno()));
      CHECK(exception_in(reply, req[1]) == MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
      ++answered;
    }
  }
  CHECK(answered == 80);
  // libmodbus's own answer to an unknown function sleeps and then flushes what
  // the client sent meanwhile: a read sent right behind it would be lost. The
  // module answers both, in order.
  const auto replies = raw_tcp_pipeline(d.port(), {{1, {0x41, 0x00, 0x01}}, {1, {0x03, 0x00, 0x00, 0x00, 0x01}}});
  REQUIRE(replies.size() == 2);
  CHECK(replies[0].first == 1);
  CHECK(replies[0].second == std::vector<std::uint8_t>{0xC1, MODBUS_EXCEPTION_ILLEGAL_FUNCTION});
  CHECK(replies[1].first == 2);
  CHECK(replies[1].second.size() == 4);
  CHECK(replies[1].second[0] == 0x03);
  CHECK(holding_snapshot(c) == before);
  // The connection is still good.
  CHECK(c.read("status.map_version") == registers::kMapVersion);
}

TEST_CASE("exception 02: an unmapped address, nothing changes") {
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto before = holding_snapshot(c);
  // Unmapped holding addresses: between the globals, inside a per-axis block's gap, far away.
  // (X's offsets 15 and 16 are axis.x.drive_home_timeout_s and axis.x.kind.)
  for (std::uint16_t a : {49, 114, 117, 150, 700, 9000, 65535}) {
    INFO("holding " << a);
    REQUIRE(registers::find_register(registers::Unit::module, registers::Table::holding_register, a) == nullptr);
    CHECK(fc6(c, a, 1) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
    CHECK(fc16(c, a, {1}) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  }
  // A write that starts mapped and runs into a gap: refused whole.
  const auto shared = reg("axis.x.shared_limit");
  CHECK(fc16(c, shared.address, {1, 1234, 7}) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  CHECK(c.read("axis.x.shared_limit") == 0);
  CHECK(c.read("axis.x.jog_feedrate") == reg("axis.x.jog_feedrate").default_raw);
  // Reads of ranges with no register at all; coils too.
  std::uint16_t w[10];
  std::uint8_t bits[10];
  CHECK(modbus_read_registers(c.ctx(), 9000, 10, w) == -1);
  CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  CHECK(modbus_read_input_registers(c.ctx(), 9000, 10, w) == -1);
  CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  CHECK(modbus_read_bits(c.ctx(), 5000, 10, bits) == -1);
  CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  CHECK(modbus_write_bit(c.ctx(), 5000, 1) == -1);
  CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  // On the simulator unit as well.
  c.use_unit(247);
  CHECK(fc6(c, 9000, 1) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  c.use_unit(1);
  CHECK(holding_snapshot(c) == before);
}

TEST_CASE("exception 02: a write to a read-only register, nothing changes") {
  using registers::Table;
  // The read-only data are the input registers and discrete inputs: no coil or
  // holding register is read-only. One that is added needs its own case here.
  for (const registers::Register& r : registers::all_registers()) {
    if (r.table != Table::holding_register && r.table != Table::coil) continue;
    INFO(r.name() << " is read-only in a writable table: write it in this test");
    CHECK(r.writable());
  }
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto before = holding_snapshot(c);
  const auto positions = [&] {
    std::vector<std::int64_t> p;
    for (const char* axis : {"x", "y", "z", "a", "b", "c"}) p.push_back(c.read(std::string("axis.") + axis + ".position"));
    return p;
  };
  const auto at_rest = positions();
  const std::int64_t count_before = c.read("status.refusal_count");
  constexpr std::int64_t kNotMapped = 1;  // hmi_maps/refusals.csv
  std::int64_t refused = 0;
  std::vector<std::string> written;
  // Every status word and bit, on both units, written with the write functions
  // at its own address where no setting or command shares that address.
  for (const registers::Register& r : registers::all_registers()) {
    const bool word = r.table == Table::input_register;
    if (!word && r.table != Table::discrete_input) continue;
    if (registers::find_register(r.unit, word ? Table::holding_register : Table::coil, r.address) != nullptr) continue;
    INFO(r.name() << " at " << r.address);
    c.use_unit(r.unit == registers::Unit::module ? 1 : 247);
    if (word) {
      CHECK(fc6(c, r.address, 1) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
      CHECK(fc16(c, r.address, std::vector<std::uint16_t>(r.words(), 1)) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
      refused += 2;
    } else {
      CHECK(modbus_write_bit(c.ctx(), r.address, 1) == -1);
      CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
      ++refused;
    }
    c.use_unit(1);
    // Refused as what it is, at that address.
    CHECK(c.read("status.last_refused_register") == r.address);
    CHECK(c.read("status.last_refusal_reason") == kNotMapped);
    written.push_back(r.name());
  }
  // The loop ran over what exists: status words of the module and bits of the simulator among them.
  for (const char* name : {"status.interlocks", "status.global_alarm", "status.alarm_axis", "sim.x.sensor"}) {
    INFO(name);
    CHECK(std::find(written.begin(), written.end(), name) != written.end());
  }
  CHECK(c.read("status.refusal_count") == ((count_before + refused) & 0xFFFF));
  CHECK(holding_snapshot(c) == before);
  CHECK(positions() == at_rest);
  CHECK(c.read("status.state") == static_cast<std::int64_t>(homing::MachineState::not_homed));
}

TEST_CASE("exception 02: a write covering one half of a 32-bit value, nothing changes") {
  Daemon d;
  Client c = Client::tcp(d.port());
  c.set("axis.x.pull_off", 1500);
  const auto before = holding_snapshot(c);
  const auto& pull_off = reg("axis.x.pull_off");
  REQUIRE(pull_off.words() == 2);
  CHECK(fc6(c, pull_off.address, 0) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);      // high word alone
  CHECK(fc6(c, pull_off.address + 1, 7) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);  // low word alone
  CHECK(fc16(c, pull_off.address, {0}) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  CHECK(fc16(c, pull_off.address + 1, {0, 0}) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);  // straddles two values
  // FC 23 whose write half covers one word.
  std::uint16_t w = 9, dest[2];
  CHECK(modbus_write_and_read_registers(c.ctx(), pull_off.address + 1, 1, &w, pull_off.address, 2, dest) == -1);
  CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  // Same on the simulator unit.
  const auto& actual = reg("sim.x.actual_position");
  const auto actual_before = c.read("sim.x.actual_position");
  c.use_unit(247);
  CHECK(fc6(c, actual.address + 1, 5) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  c.use_unit(1);
  CHECK(c.read("sim.x.actual_position") == actual_before);
  CHECK(c.read("axis.x.pull_off") == 1500);
  CHECK(holding_snapshot(c) == before);
}

TEST_CASE("exception 03: quantities beyond the spec's limits, nothing changes") {
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto before = holding_snapshot(c);
  struct Case {
    const char* what;
    std::vector<std::uint8_t> req;
  };
  std::vector<Case> cases{
      {"FC3 126 registers", pdu16(1, 0x03, 100, 126)},
      {"FC4 126 registers", pdu16(1, 0x04, 100, 126)},
      {"FC3 0 registers", pdu16(1, 0x03, 100, 0)},
      {"FC1 2001 bits", pdu16(1, 0x01, 0, 2001)},
      {"FC2 2001 bits", pdu16(1, 0x02, 0, 2001)},
      // 124 registers cannot fit a 253-byte PDU: the quantity field says 124, with all the data that fits.
      {"FC16 124 registers", write_multiple(1, 100, 124, 248, 123, 1)},
      {"FC16 124 registers, byte count 0", write_multiple(1, 100, 124, 0, 0, 1)},
      {"FC16 byte count not 2 x quantity", write_multiple(1, 100, 2, 3, 2, 1)},
  };
  {
    // FC 15 with 1969 coils.
    std::vector<std::uint8_t> r = pdu16(1, 0x0F, 0, 1969);
    r.push_back(247);
    r.insert(r.end(), 245, 0);  // as much as fits; the quantity is refused first
    cases.push_back({"FC15 1969 coils", r});
  }
  {
    // FC 23 reading 126.
    std::vector<std::uint8_t> r = pdu16(1, 0x17, 100, 126);
    for (std::uint8_t b : {0x00, 0x67, 0x00, 0x01, 0x02, 0x00, 0x05}) r.push_back(b);  // write 1 reg at 103 = 5
    cases.push_back({"FC23 read 126", r});
  }
  for (const auto& cs : cases) {
    INFO(cs.what << ", errno " << modbus_strerror(c.last_errno()));
    const auto reply = c.raw(cs.req);
    CHECK(exception_in(reply, cs.req[1]) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  }
  // The limits themselves are fine.
  std::uint16_t w[125];
  std::uint8_t bits[2000];
  CHECK(modbus_read_registers(c.ctx(), 100, 125, w) == 125);
  CHECK(modbus_read_input_registers(c.ctx(), 100, 125, w) == 125);
  CHECK(modbus_read_bits(c.ctx(), 0, 2000, bits) == 2000);
  CHECK(modbus_read_input_bits(c.ctx(), 0, 2000, bits) == 2000);
  CHECK(holding_snapshot(c) == before);
}

TEST_CASE("exception 03: a write of more registers or coils than the spec allows, sent whole in a frame longer than "
          "the standard's, is answered and the connection goes on") {
  // What pymodbus sends for write_registers(100, [..124 values..]): libmodbus
  // refuses to build such a frame, another client may not.
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto before = holding_snapshot(c);
  std::vector<std::uint8_t> registers124 = write_multiple(1, 100, 124, 248, 124, 1);
  registers124.erase(registers124.begin());  // the unit goes in the MBAP header
  std::vector<std::uint8_t> coils2000{0x0F, 0x00, 0x00, 0x07, 0xD0, 250};
  coils2000.resize(6 + 250, 0xFF);
  const auto& version = reg("status.map_version");
  const std::vector<std::uint8_t> read_version{0x04, static_cast<std::uint8_t>(version.address >> 8),
                                               static_cast<std::uint8_t>(version.address), 0, 1};
  // On one connection, back to back: each refused, and the read after them answered in step.
  const auto replies = test_support::raw_tcp_pipeline(d.port(), {{1, registers124}, {1, coils2000}, {1, read_version}});
  REQUIRE(replies.size() == 3);
  CHECK(replies[0] == std::pair<std::uint16_t, std::vector<std::uint8_t>>{1, {0x90, 0x03}});
  CHECK(replies[1] == std::pair<std::uint16_t, std::vector<std::uint8_t>>{2, {0x8F, 0x03}});
  CHECK(replies[2] == std::pair<std::uint16_t, std::vector<std::uint8_t>>{
                          3, {0x04, 0x02, 0x00, static_cast<std::uint8_t>(registers::kMapVersion)}});
  CHECK(holding_snapshot(c) == before);
}

TEST_CASE("exception 03: a value out of range, nothing changes") {
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto before = holding_snapshot(c);
  const std::vector<std::pair<const char*, std::int64_t>> bad{
      {"axis.x.mode", homing::kHomingModeCount},  // the first number past the mode table
      {"axis.x.direction", 2},          {"axis.y.seek_feedrate", 0},
      {"axis.z.debounce_ms", 1001}, {"global.watchdog_ms", 60001},    {"sequence.step1", 64},
      {"axis.x.max_seek_travel", 100000001}, {"axis.x.pull_off", -1}, {"axis.x.home_position", -100000001},
      {"global.allowed_without_homing", 3},
  };
  for (const auto& [name, raw] : bad) {
    INFO(name << " = " << raw);
    CHECK(c.write(name, raw) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  }
  // The simulator unit validates too.
  CHECK(c.write("sim.x.fault", static_cast<std::int64_t>(std::size(homing::sim::kFaultInfo))) ==
        MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.read("sim.x.fault") == 0);
  // A coil written with a value other than 0x0000 / 0xFF00.
  const auto reply = c.raw(pdu16(1, 0x05, reg("host.homing_permit").address, 0x1234));
  CHECK(exception_in(reply, 0x05) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.read("host.homing_permit") == 0);
  CHECK(holding_snapshot(c) == before);
}

TEST_CASE("exception 03: a cross-field setting combination that cannot work, nothing changes") {
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto before = holding_snapshot(c);
  // Default X: acceleration 500 mm/s², max stop distance 10 mm. 12000 mm/min =
  // 200 mm/s stops in 200²/(2·500) = 40 mm: too fast.
  REQUIRE(c.read("axis.x.acceleration") == 500);
  REQUIRE(c.read("axis.x.max_stop_distance") == 10000);
  CHECK(c.write("axis.x.seek_feedrate", 12000) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  // Latch not slower than seek.
  CHECK(c.write("axis.x.latch_feedrate", 1000) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(holding_snapshot(c) == before);
  // The same feedrate with a higher acceleration in the same request works:
  // the check is made on the request as a whole (200²/(2·5000) = 4 mm).
  const auto& seek = reg("axis.x.seek_feedrate");
  REQUIRE(reg("axis.x.acceleration").address == seek.address + 2);
  CHECK(fc16(c, seek.address, {12000, 100, 5000}) == 0);
  CHECK(c.read("axis.x.seek_feedrate") == 12000);
  CHECK(c.read("axis.x.acceleration") == 5000);
  // And then lowering the acceleration alone is the combination that cannot work.
  CHECK(c.write("axis.x.acceleration", 500) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.read("axis.x.acceleration") == 5000);
}

TEST_CASE("exception 06: a settings write during a homing cycle, a placed carriage while it moves") {
  Daemon d({.time_scale = 5});
  Client c = Client::tcp(d.port());
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("axis.z.velocity") != 0; }, 2s));
  REQUIRE(c.read("status.homing") == 1);
  const auto before = holding_snapshot(c);
  CHECK(c.write("axis.x.pull_off", 2500) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  CHECK(c.write("axis.z.seek_feedrate", 900) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  CHECK(c.write("sequence.step3", 1) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  // Z is moving: placing its carriage is refused; it goes on from where it is.
  const auto z0 = c.read("sim.z.actual_position");
  CHECK(c.write("sim.z.actual_position", um(50)) == MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
  std::this_thread::sleep_for(50ms);
  const auto z1 = c.read("sim.z.actual_position");
  CHECK(z1 < z0);          // still seeking toward the negative end
  CHECK(z1 > um(50) + 5000);  // and not placed at 50 mm (it moves ~1.7 mm per 20 ms here)
  // Values that are not settings are still accepted during the cycle.
  CHECK(c.write("host.heartbeat", 7) == 0);
  CHECK(holding_snapshot(c) != before);  // host.heartbeat changed...
  c.set("host.heartbeat", 0);
  CHECK(holding_snapshot(c) == before);  // ...and nothing else did
  REQUIRE(wait_until([&] { return c.read("status.state") == static_cast<int>(homing::MachineState::homed); }, 20s));
  CHECK(c.read("axis.x.pull_off") == reg("axis.x.pull_off").default_raw);
  // Once the cycle is over the same write is accepted.
  CHECK(c.write("axis.x.pull_off", 2500) == 0);
  CHECK(c.read("axis.x.pull_off") == 2500);
}

TEST_CASE("a multi-register FC16 write is all or nothing") {
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto before = holding_snapshot(c);
  const auto& mode = reg("axis.x.mode");
  const auto& jog = reg("axis.x.jog_feedrate");
  const int n = jog.address - mode.address + 1;  // the 16-bit block 100..113
  auto block = c.holding(mode.address, n);
  REQUIRE(block);
  std::vector<std::uint16_t> words = *block;
  words[reg("axis.x.direction").address - mode.address] = 1;
  words[reg("axis.x.jog_feedrate").address - mode.address] = 2000;
  words[reg("axis.x.debounce_ms").address - mode.address] = 5000;  // the bad one, in the middle
  CHECK(fc16(c, mode.address, words) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.holding(mode.address, n) == block);

  // The 32-bit block: five lengths, the third out of range.
  const auto& first = reg("axis.y.max_seek_travel");
  std::vector<std::uint16_t> lengths;
  for (const char* name : {"axis.y.max_seek_travel", "axis.y.max_stop_distance", "axis.y.max_backoff",
                           "axis.y.pull_off", "axis.y.home_position"}) {
    const std::int64_t raw = std::string_view(name) == "axis.y.max_backoff" ? -5 : 4321;
    for (auto w : words_of(name, raw)) lengths.push_back(w);
  }
  CHECK(fc16(c, first.address, lengths) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(holding_snapshot(c) == before);

  // Fixed, the same request is applied whole.
  words[reg("axis.x.debounce_ms").address - mode.address] = 5;
  CHECK(fc16(c, mode.address, words) == 0);
  CHECK(c.read("axis.x.direction") == 1);
  CHECK(c.read("axis.x.jog_feedrate") == 2000);
  CHECK(c.read("axis.x.debounce_ms") == 5);
}

TEST_CASE("FC23 read/write registers: the write is applied before the read, a bad write changes nothing") {
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto& pull_off = reg("axis.z.pull_off");
  const auto& first = reg("axis.z.max_seek_travel");
  const auto w = words_of("axis.z.pull_off", 2750);
  std::uint16_t dest[10] = {};
  REQUIRE(modbus_write_and_read_registers(c.ctx(), pull_off.address, 2, w.data(), first.address, 10, dest) == 10);
  const int at = pull_off.address - first.address;
  CHECK(registers::decode_words(pull_off, std::span<const std::uint16_t>(dest + at, 2),
                                registers::WordOrder::high_first) == 2750);
  CHECK(c.read("axis.z.pull_off") == 2750);
  // Reading input-only addresses as holding registers via FC 23 is refused before any write.
  const auto bad = words_of("axis.z.pull_off", 1111);
  CHECK(modbus_write_and_read_registers(c.ctx(), pull_off.address, 2, bad.data(), 9000, 4, dest) == -1);
  CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  CHECK(c.read("axis.z.pull_off") == 2750);
  // A write out of range: 03, nothing applied.
  const auto out = words_of("axis.z.pull_off", -1);
  CHECK(modbus_write_and_read_registers(c.ctx(), pull_off.address, 2, out.data(), first.address, 10, dest) == -1);
  CHECK(exception_of(errno) == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  CHECK(c.read("axis.z.pull_off") == 2750);
}

TEST_CASE("FC43/14 read device identification answers our identity, not libmodbus's") {
  Daemon d;
  auto object_map = [](const std::vector<std::uint8_t>& reply) {
    std::map<int, std::string> objects;
    if (reply.size() < 7) return objects;
    std::size_t i = 7;
    for (int k = 0; k < reply[6] && i + 2 <= reply.size(); ++k) {
      const int id = reply[i], len = reply[i + 1];
      if (i + 2 + len > reply.size()) break;
      objects[id] = std::string(reply.begin() + static_cast<long>(i) + 2, reply.begin() + static_cast<long>(i) + 2 + len);
      i += 2 + len;
    }
    return objects;
  };
  const auto basic = raw_tcp_transaction(d.port(), 1, {0x2B, 0x0E, 0x01, 0x00});
  REQUIRE(basic.size() >= 7);
  CHECK(basic[0] == 0x2B);
  CHECK(basic[1] == 0x0E);
  CHECK(basic[2] == 0x01);
  const auto objects = object_map(basic);
  REQUIRE(objects.size() == 3);
  CHECK_FALSE(objects.at(0).empty());  // vendor
  CHECK_FALSE(objects.at(1).empty());  // product code
  CHECK(objects.at(2) == HOMING_VERSION);  // revision: the build's version
  for (const auto& [id, text] : objects) CHECK(text.find("libmodbus") == std::string::npos);
  const auto regular = object_map(raw_tcp_transaction(d.port(), 1, {0x2B, 0x0E, 0x02, 0x00}));
  CHECK(regular.size() >= 4);
  const auto one = object_map(raw_tcp_transaction(d.port(), 1, {0x2B, 0x0E, 0x04, 0x01}));
  REQUIRE(one.size() == 1);
  CHECK(one.at(1) == objects.at(1));
  // A bad read code: exception 03; an unknown MEI type: 01.
  CHECK(raw_tcp_transaction(d.port(), 1, {0x2B, 0x0E, 0x05, 0x00}) == std::vector<std::uint8_t>{0xAB, 0x03});
  CHECK(raw_tcp_transaction(d.port(), 1, {0x2B, 0x0D, 0x01, 0x00}) == std::vector<std::uint8_t>{0xAB, 0x01});
}

TEST_CASE("over TCP unit ids 0xFF and 0 address the module itself, as the TCP implementation guide says") {
  Daemon d;
  Client c = Client::tcp(d.port());
  c.use_unit(0xFF);
  std::uint16_t w[1];
  REQUIRE(modbus_read_input_registers(c.ctx(), reg("status.map_version").address, 1, w) == 1);
  CHECK(w[0] == registers::kMapVersion);
  REQUIRE(modbus_write_register(c.ctx(), reg("axis.x.jog_feedrate").address, 1234) == 1);
  c.use_unit(1);
  CHECK(c.read("axis.x.jog_feedrate") == 1234);
  // Unit 0 in the MBAP header (raw, so no client library treats it as a broadcast).
  const auto answer = raw_tcp_transaction(d.port(), 0, {0x04, static_cast<std::uint8_t>(reg("status.map_version").address >> 8),
                                                       static_cast<std::uint8_t>(reg("status.map_version").address & 0xFF), 0x00, 0x01});
  REQUIRE(answer.size() == 4);
  CHECK(answer[0] == 0x04);
  CHECK(((answer[2] << 8) | answer[3]) == registers::kMapVersion);
}

TEST_CASE("an unknown unit id over TCP is exception 0B, nothing changes") {
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto before = holding_snapshot(c);
  for (int unit : {2, 5, 100, 246, 254}) {
    INFO("unit " << unit);
    c.use_unit(unit);
    std::uint16_t w[2];
    CHECK(modbus_read_input_registers(c.ctx(), 0, 1, w) == -1);
    CHECK(exception_of(errno) == MODBUS_EXCEPTION_GATEWAY_TARGET);
    CHECK(modbus_write_register(c.ctx(), reg("axis.x.jog_feedrate").address, 1234) == -1);
    CHECK(exception_of(errno) == MODBUS_EXCEPTION_GATEWAY_TARGET);
    CHECK(modbus_write_bit(c.ctx(), reg("cmd.home_all").address, 1) == -1);
    CHECK(exception_of(errno) == MODBUS_EXCEPTION_GATEWAY_TARGET);
  }
  c.use_unit(1);
  CHECK(holding_snapshot(c) == before);
  CHECK(c.read("status.homing") == 0);
  CHECK(c.read("status.last_command_result") == 0);
}
