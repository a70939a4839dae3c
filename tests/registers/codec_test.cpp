// Raw integers <-> words <-> engineering values, for every type and both word orders.
#include <catch2/catch.hpp>

#include <array>

#include "registers/codec.hpp"
#include "registers/lookup.hpp"
#include "tests/support/named_registers.hpp"

using namespace registers;

namespace {
using test_support::reg;  // throws, naming the register, when the table has none

std::int64_t round_trip(const Register& r, std::int64_t raw, WordOrder order) {
  std::array<std::uint16_t, 2> w{};
  encode_words(r, raw, order, std::span(w).first(r.words()));
  return decode_words(r, std::span<const std::uint16_t>(w).first(r.words()), order);
}
}  // namespace

TEST_CASE("every type survives encode and decode in both word orders") {
  const auto order = GENERATE(WordOrder::high_first, WordOrder::low_first);
  // i32, including negative values and the extremes
  for (std::int64_t v : {0LL, 1LL, -1LL, -1'000'000LL, 123'456'789LL, -2147483648LL, 2147483647LL})
    CHECK(round_trip(reg("axis.x.home_position"), v, order) == v);
  // u32
  for (std::int64_t v : {0LL, 65536LL, 4294967295LL}) CHECK(round_trip(reg("status.homing_cycles"), v, order) == v);
  // u16, enum, bitmask, bool-as-u16
  for (std::int64_t v : {0LL, 1LL, 65535LL}) CHECK(round_trip(reg("host.heartbeat"), v, order) == v);
  CHECK(round_trip(reg("axis.x.mode"), 8, order) == 8);
  CHECK(round_trip(reg("sequence.step1"), 63, order) == 63);
  CHECK(round_trip(reg("axis.x.sensor_nc"), 1, order) == 1);
  CHECK(round_trip(reg("cmd.home_all"), 1, order) == 1);
}

TEST_CASE("32-bit words go high first by default and swap with low_first") {
  const Register& r = reg("axis.x.home_position");
  std::array<std::uint16_t, 2> w{};
  encode_words(r, -2, WordOrder::high_first, w);
  CHECK(w == std::array<std::uint16_t, 2>{0xFFFF, 0xFFFE});
  encode_words(r, 0x12345678, WordOrder::high_first, w);
  CHECK(w == std::array<std::uint16_t, 2>{0x1234, 0x5678});
  encode_words(r, 0x12345678, WordOrder::low_first, w);
  CHECK(w == std::array<std::uint16_t, 2>{0x5678, 0x1234});
}

TEST_CASE("lengths are raw micrometres, feedrates raw mm/min") {
  const Register& pull = reg("axis.x.pull_off");
  CHECK(to_engineering(pull, 1500) == 1.5);
  CHECK(to_raw(pull, 1.5) == 1500);
  CHECK(to_raw(pull, -0.0004) == 0);
  CHECK(to_raw(pull, 0.1) == 100);
  CHECK(to_engineering(pull, 100) == 0.1);
  const Register& seek = reg("axis.x.seek_feedrate");
  CHECK(to_engineering(seek, 1200) == 1200.0);
  CHECK(to_raw(seek, 1200.4) == 1200);
}

TEST_CASE("status values too large for their register saturate instead of wrapping") {
  const Register& pos = reg("axis.x.position");
  CHECK(to_raw(pos, 1e9) == 2147483647LL);
  CHECK(to_raw(pos, -1e9) == -2147483648LL);
}

TEST_CASE("status reads come from the engine's status and the runtime extras") {
  homing::Settings s;
  HostRegisters h;
  homing::Status st;
  StatusExtras ex;
  st.state = homing::MachineState::alarm;
  st.axes[1].position_mm = -12.345;
  st.axes[1].alarm.code = homing::AlarmCode::not_released;
  st.axes[1].alarm.phase = homing::Phase::back_off;
  st.axes[2].homed = true;
  st.homing_cycles = 70000;
  ex.correction_spread_mm[0] = 0.004;
  const ModuleView view{s, h, st, ex};
  CHECK(read_raw(reg("status.state"), view) == 3);
  CHECK(read_raw(reg("axis.y.position"), view) == -12345);
  CHECK(read_raw(reg("axis.y.alarm"), view) == 4);
  CHECK(read_raw(reg("axis.y.alarm_phase"), view) == 6);
  CHECK(read_raw(reg("status.alarm_axis"), view) == 2);
  CHECK(read_raw(reg("axis.z.homed"), view) == 1);
  CHECK(read_raw(reg("axis.x.correction_spread"), view) == 4);

  // FC 4 over status.homing_cycles and the following registers
  std::array<std::uint16_t, 3> words{};
  const Register& cycles = reg("status.homing_cycles");
  REQUIRE(!read_module_words(Table::input_register, cycles.address, words, WordOrder::high_first, view));
  CHECK(words[0] == 1);
  CHECK(words[1] == 70000 - 65536);
}

TEST_CASE("a read over a gap in the map reads zeros, a read of nothing mapped is exception 02") {
  homing::Settings s;
  HostRegisters h;
  homing::Status st;
  StatusExtras ex;
  const ModuleView view{s, h, st, ex};
  std::array<std::uint16_t, 30> block{};
  block.fill(0xAAAA);
  REQUIRE(!read_module_words(Table::holding_register, 0, block, WordOrder::high_first, view));
  CHECK(block[6] == 0);  // gap between sequence.step6 and global.allowed_without_homing
  std::array<std::uint16_t, 4> nothing{};
  const auto refusal = read_module_words(Table::holding_register, 90, nothing, WordOrder::high_first, view);
  REQUIRE(refusal);
  CHECK(refusal->code == ExceptionCode::illegal_data_address);
}

TEST_CASE("a read that starts on the second word of a 32-bit value returns that word") {
  homing::Settings s;
  HostRegisters h;
  homing::Status st;
  st.axes[1].position_mm = -12.345;
  StatusExtras ex;
  const ModuleView view{s, h, st, ex};
  const Register& pos = reg("axis.y.position");
  std::array<std::uint16_t, 2> whole{}, second{};
  REQUIRE(!read_module_words(Table::input_register, pos.address, whole, WordOrder::high_first, view));
  REQUIRE(!read_module_words(Table::input_register, pos.address + 1, second, WordOrder::high_first, view));
  CHECK(second[0] == whole[1]);
  CHECK(static_cast<std::int32_t>(std::uint32_t{whole[0]} << 16 | whole[1]) == -12345);
}

TEST_CASE("a bit read over gaps reads the mapped bits and zeros between them") {
  homing::Settings s;
  HostRegisters h;
  homing::Status st;
  st.axes[2].homed = true;
  StatusExtras ex;
  const ModuleView view{s, h, st, ex};
  const Register& homed_z = reg("axis.z.homed");
  std::array<std::uint8_t, 64> bits{};
  bits.fill(7);
  REQUIRE(!read_module_bits(Table::discrete_input, homed_z.address - 10, bits, view));
  for (std::size_t i = 0; i < bits.size(); ++i) {
    INFO("bit " << i);
    CHECK(bits[i] == (i == 10 ? 1 : 0));
  }
}

TEST_CASE("command coils map to command ids with their axis") {
  const auto home_y = command_of(reg("cmd.home.y"), true);
  REQUIRE(home_y);
  CHECK(home_y->command == Command::home_axis);
  CHECK(home_y->axis == 1);
  CHECK(command_of(reg("cmd.jog_minus.c"), false) == CommandRequest{Command::jog_minus, 5, false});
  CHECK(command_of(reg("host.homing_permit"), true)->command == Command::homing_permit);
  CHECK_FALSE(command_of(reg("axis.x.mode"), true));
}

TEST_CASE("every module row is bound: reading any of them never throws") {
  homing::Settings s;
  HostRegisters h;
  homing::Status st;
  StatusExtras ex;
  const ModuleView view{s, h, st, ex};
  for (const Register& r : registers_of(Unit::module)) {
    INFO(r.name());
    CHECK_NOTHROW(read_raw(r, view));
  }
}

TEST_CASE("the measurement's figures read as micrometres at their per-axis input registers, and cmd.measure.<a> maps to its command with the axis") {
  homing::Settings s;
  HostRegisters h;
  homing::Status st;
  StatusExtras ex;
  st.axes[2].measurement = {148.672, -0.5, 148.172, 176};
  const ModuleView view{s, h, st, ex};
  CHECK(reg("axis.z.measured_travel").address == 100 + 100 * 2 + 44);
  CHECK(read_raw(reg("axis.z.measured_travel"), view) == 148672);
  CHECK(read_raw(reg("axis.z.measured_soft_limit_min"), view) == -500);
  CHECK(read_raw(reg("axis.z.measured_soft_limit_max"), view) == 148172);
  CHECK(read_raw(reg("axis.z.measured_max_seek_travel"), view) == 176000);
  CHECK(read_raw(reg("axis.x.measured_travel"), view) == 0);  // no measurement yet
  CHECK(reg("cmd.measure.b").address == 100 + 10 * 4 + 7);
  CHECK(command_of(reg("cmd.measure.b"), true) == CommandRequest{Command::measure_axis, 4, true});
}
