// The simulator unit: its defaults make a machine that homes with the module's
// defaults, and its writes are all or nothing like the module's.
#include <catch2/catch.hpp>

#include <array>

#include "homing/engine.hpp"
#include "homing/sim/simulator.hpp"
#include "registers/defaults.hpp"
#include "registers/lookup.hpp"
#include "registers/sim_bindings.hpp"
#include "tests/support/named_registers.hpp"

using namespace registers;

using test_support::reg;  // throws, naming the register, when the table has none

TEST_CASE("simulator defaults come from the table") {
  const auto c = default_sim_config();
  CHECK(c.axes[0].actual_position_mm == 100);
  CHECK(c.axes[0].sensor_min_mm == -1000);
  CHECK(c.axes[0].sensor_max_mm == 0);
  CHECK(c.axes[0].hysteresis_mm == 0.05);
  CHECK(c.axes[0].noise_mm == 0.002);
  CHECK(c.axes[2].hard_stop_min_mm == -5);
  CHECK(c.axes[2].hard_stop_max_mm == 1000);
  CHECK(c.axes[1].index_pitch_mm == 0);
  CHECK(c.seed == 1);
}

TEST_CASE("GIVEN the default settings and the default simulated machine WHEN home all THEN every axis is homed") {
  const homing::Settings settings = default_settings();
  homing::sim::Simulator sim(default_sim_config());
  homing::Engine engine;
  const double dt = 0.001;
  bool started = false;
  for (int period = 0; period < 120'000; ++period) {
    homing::Inputs in = sim.inputs();
    in.commands.home_all = period == 1;
    const auto r = engine.step(settings, in, dt);
    sim.advance(r.outputs, dt);
    started |= r.status.homing;
    if (started && !r.status.homing) break;
  }
  const auto& st = engine.status();
  INFO("state " << static_cast<int>(st.state) << ", X alarm " << static_cast<int>(st.axes[0].alarm.code)
                << ", Z alarm " << static_cast<int>(st.axes[2].alarm.code));
  REQUIRE(started);
  CHECK(st.state == homing::MachineState::homed);
  for (std::size_t a = 0; a < 3; ++a) {
    CHECK(st.axes[a].homed);
    CHECK(st.axes[a].position_mm == Approx(0).margin(0.01));  // home position 0 after pull-off
  }
}

TEST_CASE("a simulator write applies to a copy and reports lost steps and placement") {
  const auto c = default_sim_config();
  const SimSwitches sw;
  SimReadback rb;
  rb.actual_position_mm[0] = 100;
  const Register& lose = reg("sim.x.lose_steps");
  std::array<std::uint16_t, 2> w{};
  encode_words(lose, -1500, WordOrder::high_first, w);
  const auto ok = validate_sim_write(Table::holding_register, lose.address, w, WordOrder::high_first, c, sw, rb);
  REQUIRE(ok);
  CHECK(ok->lose_steps_mm[0] == -1.5);
  CHECK(sim_raw(lose, ok->config, ok->switches, rb) == 0);  // reads back 0

  const Register& fault = reg("sim.y.fault");
  // The first number past the last simulated fault.
  const std::array<std::uint16_t, 1> past{static_cast<std::uint16_t>(std::size(homing::sim::kFaultInfo))};
  const auto refused = validate_sim_write(Table::holding_register, fault.address, past, WordOrder::high_first, c, sw, rb);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ExceptionCode::illegal_data_value);

  const Register& estop = reg("sim.estop");
  const std::array<std::uint16_t, 1> on{1};
  const auto pressed = validate_sim_write(Table::coil, estop.address, on, WordOrder::high_first, c, sw, rb);
  REQUIRE(pressed);
  CHECK(pressed->switches.estop);
}

TEST_CASE("a carriage placed beyond its hard stops is refused with its reason and the placement register") {
  const auto c = default_sim_config();  // Z between its stops at -5 and 1000 mm
  const SimSwitches sw;
  const SimReadback rb;
  const Register& actual = reg("sim.z.actual_position");
  const auto place = [&](std::int64_t um) {
    std::array<std::uint16_t, 2> w{};
    encode_words(actual, um, WordOrder::high_first, w);
    return validate_sim_write(Table::holding_register, actual.address, w, WordOrder::high_first, c, sw, rb);
  };
  for (const std::int64_t um : {-5'001, 1'000'001}) {
    const auto refused = place(um);
    REQUIRE_FALSE(refused);
    CHECK(refused.error().code == ExceptionCode::illegal_data_value);
    CHECK(refused.error().reason == RefusalReason::beyond_hard_stop);
    CHECK(refused.error().address == actual.address);
    CHECK(refused.error().message.find("sim.z.actual_position") != std::string::npos);
  }
  // At a stop is where a carriage can be.
  REQUIRE(place(-5'000));
  CHECK(place(-5'000)->placed[2]);
  REQUIRE(place(1'000'000));
  // Against the stops as they are (a stop written before makes room).
  auto moved = c;
  moved.axes[2].hard_stop_min_mm = -20;
  std::array<std::uint16_t, 2> w{};
  encode_words(actual, -10'000, WordOrder::high_first, w);
  const auto placed = validate_sim_write(Table::holding_register, actual.address, w, WordOrder::high_first, moved, sw, rb);
  REQUIRE(placed);
  CHECK(placed->config.axes[2].actual_position_mm == -10);
}

TEST_CASE("a block write of a carriage's stops that writes its position back unchanged places nothing and the stop "
          "pushes it along") {
  const auto c = default_sim_config();
  const SimSwitches sw;
  SimReadback rb;
  rb.actual_position_mm[2] = c.axes[2].actual_position_mm;
  const Register& actual = reg("sim.z.actual_position");
  const Register& stop_max = reg("sim.z.hard_stop_max");
  // Every register from the position through the upper stop, as read back.
  std::vector<std::uint16_t> words(stop_max.address + 2 - actual.address);
  for (std::uint16_t at = actual.address; at < stop_max.address + 2;) {
    const Register* r = find_register(Unit::simulator, Table::holding_register, at);
    REQUIRE(r);
    encode_words(*r, sim_raw(*r, c, sw, rb), WordOrder::high_first,
                 std::span(words).subspan(at - actual.address, r->words()));
    at = static_cast<std::uint16_t>(at + r->words());
  }
  // The upper stop lowered below the carriage.
  const auto below = static_cast<std::int64_t>((c.axes[2].actual_position_mm - 10) * 1000);
  encode_words(stop_max, below, WordOrder::high_first, std::span(words).subspan(stop_max.address - actual.address, 2));
  const auto ok = validate_sim_write(Table::holding_register, actual.address, words, WordOrder::high_first, c, sw, rb);
  REQUIRE(ok);
  CHECK_FALSE(ok->placed[2]);
  homing::sim::Simulator sim(c);
  sim.set_axis_config(2, ok->config.axes[2]);
  CHECK(sim.actual_position_mm(2) == Approx(c.axes[2].actual_position_mm - 10));
}

TEST_CASE("every simulator row is bound: reading any of them never throws") {
  const auto c = default_sim_config();
  for (const Register& r : registers_of(Unit::simulator)) {
    INFO(r.name());
    CHECK_NOTHROW(sim_raw(r, c, SimSwitches{}, SimReadback{}));
  }
}
