// The simulated machine, driven the way the engine drives it: the test keeps
// the engine-side motor state by integrating the same commands.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "homing/motion.hpp"
#include "homing/sim/simulator.hpp"

using namespace homing;
using namespace homing::sim;

namespace {

constexpr double kDt_s = 0.001;

struct TimedEdge {
  double time_s;  // simulator time
  bool level;     // electrical level after the edge
};

// One engine period at a time: command, simulate, integrate the motor.
struct Rig {
  Simulator sim;
  Outputs out{};
  std::array<std::vector<TimedEdge>, kAxisCount> sensor{};  // reported edges, absolute times
  std::array<std::vector<double>, kAxisCount> index{};
  std::array<bool, kAxisCount> level{};

  explicit Rig(const MachineConfig& config) : sim(config) {
    for (std::size_t i = 0; i < kAxisCount; ++i) level[i] = sim.inputs().axes[i].sensor_level;
  }

  void step(std::size_t axis, const MotionCommand& cmd) {
    out.axes[axis].motion = cmd;
    const double start_s = sim.time_s();
    sim.advance(out, kDt_s);
    for (std::size_t i = 0; i < kAxisCount; ++i) {
      out.axes[i].motor = integrate(out.axes[i].motor, out.axes[i].motion, kDt_s);
      const AxisInputs& in = sim.inputs().axes[i];
      for (std::size_t e = 0; e < in.sensor_edges.count; ++e) {
        level[i] = !level[i];
        sensor[i].push_back(TimedEdge{start_s + in.sensor_edges.time_s[e], level[i]});
      }
      for (std::size_t e = 0; e < in.index_edges.count; ++e) {
        index[i].push_back(start_s + in.index_edges.time_s[e]);
      }
      level[i] = in.sensor_level;  // a commutator switch-over changes the level without an edge
    }
  }
  void run(std::size_t axis, const MotionCommand& cmd, int periods) {
    for (int k = 0; k < periods; ++k) step(axis, cmd);
  }
  // Trapezoidal move of the motor to target, ending at rest.
  void move_to(std::size_t axis, double target_mm, double v_mm_per_s, double a_mm_per_s2) {
    for (int k = 0; k < 1000000; ++k) {
      const MotionState& m = out.axes[axis].motor;
      if (m.position_mm == target_mm && m.velocity_mm_per_s == 0) return;
      step(axis, move_to_command(m, target_mm, v_mm_per_s, a_mm_per_s2, kDt_s));
    }
    FAIL("move did not end");
  }
  double motor(std::size_t axis) const { return out.axes[axis].motor.position_mm; }
};

MachineConfig one_axis(const AxisConfig& axis) {
  MachineConfig c;
  c.axes[0] = axis;
  for (std::size_t i = 1; i < kAxisCount; ++i) {
    c.axes[i].sensor_min_mm = 1;  // a cam away from the other carriages
    c.axes[i].sensor_max_mm = -1;
  }
  return c;
}

AxisConfig cam(double min_mm, double max_mm) {
  AxisConfig a;
  a.sensor_min_mm = min_mm;
  a.sensor_max_mm = max_mm;
  return a;
}

double stddev(const std::vector<double>& xs) {
  double mean = 0;
  for (double x : xs) mean += x;
  mean /= static_cast<double>(xs.size());
  double var = 0;
  for (double x : xs) var += (x - mean) * (x - mean);
  return std::sqrt(var / static_cast<double>(xs.size() - 1));
}

}  // namespace

TEST_CASE("before any period the inputs show the machine at rest") {
  AxisConfig a = cam(5, 50);
  a.actual_position_mm = 10;
  a.absolute_offset_mm = 3;
  Simulator sim(one_axis(a));
  const AxisInputs& in = sim.inputs().axes[0];
  CHECK(in.sensor_level);
  CHECK(in.sensor_edges.count == 0);
  CHECK(in.absolute_valid);
  CHECK(in.absolute_position_mm == Approx(13));
  CHECK(sim.sensor_active(0));
  CHECK_FALSE(sim.moving(0));
}

TEST_CASE("carriage follows the motor with the starting offset as slip") {
  AxisConfig a = cam(100, 200);
  a.actual_position_mm = 10;
  Rig rig(one_axis(a));
  rig.run(0, velocity_command(50, 1000), 100);
  CHECK(rig.motor(0) == Approx(3.75));  // 1.25 mm ramp + 2.5 mm cruise
  CHECK(rig.sim.actual_position_mm(0) == Approx(rig.motor(0) + 10).margin(1e-9));
  CHECK(rig.sim.moving(0));
  rig.move_to(0, -20, 80, 1000);
  CHECK(rig.sim.actual_position_mm(0) == Approx(-10).margin(1e-9));
  CHECK_FALSE(rig.sim.moving(0));
  CHECK(rig.sim.time_s() > 0.1);
}

TEST_CASE("mechanical stop holds the carriage and the slip grows by the pushed distance") {
  AxisConfig a = cam(100, 200);
  a.actual_position_mm = 10;
  a.hard_stop_max_mm = 20;
  Rig rig(one_axis(a));
  rig.run(0, velocity_command(100, 0), 300);  // motor travels 30 mm, carriage only 10
  CHECK(rig.motor(0) == Approx(30));
  CHECK(rig.sim.actual_position_mm(0) == Approx(20));
  CHECK(rig.sim.at_hard_stop(0));
  const double pushed_mm = rig.motor(0) + 10 - 20;
  const double slip_mm = rig.sim.actual_position_mm(0) - rig.motor(0);
  CHECK(slip_mm - 10 == Approx(-pushed_mm));

  SECTION("reversing leaves the stop at once") {
    rig.step(0, velocity_command(-100, 0));
    CHECK(rig.sim.actual_position_mm(0) == Approx(19.9));
    CHECK_FALSE(rig.sim.at_hard_stop(0));
    rig.run(0, velocity_command(-100, 0), 50);
    CHECK(rig.sim.actual_position_mm(0) - rig.motor(0) == Approx(slip_mm));
  }
  SECTION("the lower stop works the same way") {
    rig.sim.set_axis_config(0, [&] {
      AxisConfig b = rig.sim.axis_config(0);
      b.hard_stop_min_mm = 15;
      return b;
    }());
    rig.run(0, velocity_command(-100, 1e6), 200);
    CHECK(rig.sim.actual_position_mm(0) == Approx(15));
    CHECK(rig.sim.at_hard_stop(0));
  }
}

TEST_CASE("sensor edge time is interpolated within the period") {
  SECTION("constant velocity") {
    Rig rig(one_axis(cam(5.0037, 50)));
    rig.run(0, velocity_command(10, 0), 600);
    REQUIRE(rig.sensor[0].size() == 1);
    CHECK(rig.sensor[0][0].time_s == Approx(0.50037).epsilon(1e-12));
    CHECK(rig.sensor[0][0].level);
    const auto edge = rig.sim.last_edge(0);
    REQUIRE(edge);
    CHECK(edge->to_active);
    CHECK(edge->time_s == Approx(0.50037).epsilon(1e-12));
    CHECK(edge->actual_mm == Approx(5.0037));
    CHECK(edge->motor_mm == Approx(5.0037));
  }
  SECTION("while accelerating, with a slip") {
    AxisConfig a = cam(5.0037, 50);
    a.actual_position_mm = 1;
    Rig rig(one_axis(a));
    rig.run(0, velocity_command(1000, 20), 1000);  // x = 1 + 10 t^2
    const double expected_s = std::sqrt(4.0037 / 10.0);
    REQUIRE(rig.sensor[0].size() == 1);
    CHECK(rig.sensor[0][0].time_s == Approx(expected_s).epsilon(1e-12));
    CHECK(rig.sim.last_edge(0)->motor_mm == Approx(4.0037));
  }
}

TEST_CASE("hysteresis: release edge lies hysteresis outside the cam") {
  AxisConfig a = cam(5, 50);
  a.hysteresis_mm = 0.5;
  Rig rig(one_axis(a));
  rig.move_to(0, 10, 20, 500);
  CHECK(rig.sim.sensor_active(0));
  rig.move_to(0, 4.7, 20, 500);
  CHECK(rig.sim.sensor_active(0));  // inside the hysteresis band
  rig.move_to(0, 0, 20, 500);
  CHECK_FALSE(rig.sim.sensor_active(0));
  const auto on = rig.sim.last_edge(0, true);
  const auto off = rig.sim.last_edge(0, false);
  REQUIRE(on);
  REQUIRE(off);
  CHECK(on->actual_mm == Approx(5));
  CHECK(off->actual_mm == Approx(4.5));
  CHECK(rig.sim.edge_count(0) == 2);
}

TEST_CASE("noise: a fixed seed repeats exactly and the edge spread matches the noise") {
  AxisConfig a = cam(5, 50);
  a.hysteresis_mm = 0.2;
  a.noise_mm = 0.05;
  auto crossings = [&](std::uint64_t seed) {
    MachineConfig c = one_axis(a);
    c.seed = seed;
    Rig rig(c);
    std::vector<double> on_mm;
    for (int k = 0; k < 400; ++k) {
      rig.move_to(0, 6, 200, 20000);
      on_mm.push_back(rig.sim.last_edge(0, true)->actual_mm);
      rig.move_to(0, 4, 200, 20000);
    }
    return on_mm;
  };
  const auto first = crossings(42);
  const auto again = crossings(42);
  const auto other = crossings(43);
  CHECK(first == again);
  CHECK(first != other);
  CHECK(stddev(first) == Approx(0.05).epsilon(0.2));
}

TEST_CASE("set_seed restarts the noise sequence") {
  AxisConfig a = cam(5, 50);
  a.noise_mm = 0.1;
  a.hysteresis_mm = 0.5;
  auto first_edge = [&](bool reseed) {
    MachineConfig c = one_axis(a);
    c.seed = reseed ? 99 : 7;
    Rig rig(c);
    if (reseed) rig.sim.set_seed(7);
    rig.sim.set_axis_config(0, [&] { AxisConfig b = a; b.noise_mm = 0.1001; return b; }());
    rig.move_to(0, 8, 50, 1000);
    return rig.sim.last_edge(0)->actual_mm;
  };
  CHECK(first_edge(true) == first_edge(false));
}

TEST_CASE("NC wiring inverts the electrical level") {
  AxisConfig a = cam(5, 50);
  a.actual_position_mm = 10;
  SECTION("normally open") {
    Simulator sim(one_axis(a));
    CHECK(sim.inputs().axes[0].sensor_level);
  }
  SECTION("normally closed") {
    a.sensor_nc = true;
    Rig rig(one_axis(a));
    CHECK_FALSE(rig.sim.inputs().axes[0].sensor_level);
    rig.move_to(0, -10, 50, 1000);  // leaves the cam: contact opens, NC level goes 1
    CHECK(rig.sim.inputs().axes[0].sensor_level);
    REQUIRE(rig.sensor[0].size() == 1);
    CHECK(rig.sensor[0][0].level);
  }
}

TEST_CASE("sensor faults set the electrical level and produce an edge at the next period start") {
  struct Case {
    Fault fault;
    bool nc;
    double position_mm;
    bool level;
  };
  // Physically: position 10 is inside the cam, 0 is outside.
  const Case cases[] = {
      {Fault::sensor_stuck_active, false, 0, true},    {Fault::sensor_stuck_active, true, 0, false},
      {Fault::sensor_stuck_inactive, false, 10, false}, {Fault::sensor_stuck_inactive, true, 10, true},
      {Fault::wire_break, false, 10, false},            {Fault::wire_break, true, 0, false},
  };
  for (const Case& c : cases) {
    CAPTURE(static_cast<int>(c.fault), c.nc, c.position_mm);
    AxisConfig a = cam(5, 50);
    a.actual_position_mm = c.position_mm;
    a.sensor_nc = c.nc;
    Rig rig(one_axis(a));
    REQUIRE(rig.sim.inputs().axes[0].sensor_level != c.level);
    a.fault = c.fault;
    rig.sim.set_axis_config(0, a);
    rig.step(0, stop_command(100));
    CHECK(rig.sim.inputs().axes[0].sensor_level == c.level);
    REQUIRE(rig.sim.inputs().axes[0].sensor_edges.count == 1);
    CHECK(rig.sim.inputs().axes[0].sensor_edges.time_s[0] == 0.0);
    // While faulted, crossing the cam changes nothing electrically.
    rig.move_to(0, 30 - c.position_mm, 100, 1000);
    CHECK(rig.sim.inputs().axes[0].sensor_level == c.level);
    CHECK(rig.sensor[0].size() == 1);
    CHECK(rig.sim.sensor_active(0) == (30 - c.position_mm > 5));
  }
}

TEST_CASE("wire break looks inactive on a NO switch and active on a NC switch") {
  for (const bool nc : {false, true}) {
    AxisConfig a = cam(5, 50);
    a.sensor_nc = nc;
    a.fault = Fault::wire_break;
    Simulator sim(one_axis(a));
    const bool level = sim.inputs().axes[0].sensor_level;
    const bool looks_active = nc ? !level : level;
    CHECK(looks_active == nc);
  }
}

TEST_CASE("drive fault: the carriage does not follow and the input reports it") {
  AxisConfig a = cam(5, 50);
  a.fault = Fault::drive_fault;
  Rig rig(one_axis(a));
  rig.run(0, velocity_command(100, 0), 100);
  CHECK(rig.sim.inputs().axes[0].drive_fault);
  CHECK(rig.motor(0) == Approx(10));
  CHECK(rig.sim.actual_position_mm(0) == 0);
  CHECK(rig.sensor[0].empty());
  a.fault = Fault::none;
  rig.sim.set_axis_config(0, a);
  rig.run(0, velocity_command(100, 0), 60);
  CHECK_FALSE(rig.sim.inputs().axes[0].drive_fault);
  CHECK(rig.sim.actual_position_mm(0) == Approx(6));
  CHECK(rig.sim.sensor_active(0));
}

TEST_CASE("bounce adds toggles after the true edge and ends on the new level") {
  AxisConfig a = cam(5, 50);
  a.hysteresis_mm = 0.5;
  a.bounce_ms = 5;
  Rig rig(one_axis(a));
  int spilled = 0;
  for (int k = 0; k < 20; ++k) {
    rig.sensor[0].clear();
    const bool entering = k % 2 == 0;
    rig.move_to(0, entering ? 8 : 2, 50, 1000);
    rig.run(0, stop_command(1000), 10);  // let the bounce die out
    const auto edge = rig.sim.last_edge(0);
    REQUIRE(edge);
    CHECK(edge->to_active == entering);
    REQUIRE((rig.sensor[0].size() == 3 || rig.sensor[0].size() == 5));
    CHECK(rig.sensor[0].front().time_s == Approx(edge->time_s));
    CHECK(rig.sensor[0].back().level == entering);
    CHECK(rig.sim.inputs().axes[0].sensor_level == entering);
    for (const TimedEdge& e : rig.sensor[0]) {
      CHECK(e.time_s >= edge->time_s);
      CHECK(e.time_s <= edge->time_s + 0.005 + 1e-12);
    }
    // The true edge is 1 ms period k; the bounce reaches into later periods.
    if (std::floor(rig.sensor[0].back().time_s / kDt_s) > std::floor(edge->time_s / kDt_s)) ++spilled;
  }
  CHECK(spilled > 0);
  CHECK(rig.sim.edge_count(0) == 20);
}

TEST_CASE("reported edges always account for every level change") {
  AxisConfig a = cam(5, 5.3);
  a.hysteresis_mm = 0.02;
  a.noise_mm = 0.05;
  a.bounce_ms = 3;
  a.index_pitch_mm = 0.7;
  Rig rig(one_axis(a));
  bool level = rig.sim.inputs().axes[0].sensor_level;
  for (int k = 0; k < 200; ++k) {
    const double target = 3 + 0.037 * ((k * 7919) % 100);
    for (int p = 0; p < 5000; ++p) {
      const MotionState& m = rig.out.axes[0].motor;
      if (m.position_mm == target && m.velocity_mm_per_s == 0) break;
      rig.step(0, move_to_command(m, target, 300, 5000, kDt_s));
      const AxisInputs& in = rig.sim.inputs().axes[0];
      REQUIRE_FALSE(in.sensor_edges.overflow);
      if (in.sensor_edges.count % 2 == 1) level = !level;
      REQUIRE(in.sensor_level == level);
      for (std::size_t e = 0; e < in.sensor_edges.count; ++e) {
        REQUIRE(in.sensor_edges.time_s[e] >= 0);
        REQUIRE(in.sensor_edges.time_s[e] <= kDt_s);
        if (e) REQUIRE(in.sensor_edges.time_s[e] >= in.sensor_edges.time_s[e - 1]);
      }
    }
  }
  CHECK(rig.sim.edge_count(0) > 100);
}

TEST_CASE("index edges fall at the pitch positions in both directions") {
  AxisConfig a = cam(100, 200);
  a.index_pitch_mm = 2;
  a.index_offset_mm = 0.5;
  Rig rig(one_axis(a));
  rig.run(0, velocity_command(10, 0), 1000);  // 0 -> 10 mm
  REQUIRE(rig.index[0].size() == 5);
  for (std::size_t k = 0; k < 5; ++k) {
    CHECK(rig.index[0][k] == Approx((0.5 + 2.0 * static_cast<double>(k)) / 10.0).epsilon(1e-12));
  }
  CHECK_FALSE(rig.sim.inputs().axes[0].index_level);
  rig.index[0].clear();
  rig.run(0, velocity_command(-10, 0), 500);  // 10 -> 5 mm: passes 8.5 and 6.5
  REQUIRE(rig.index[0].size() == 2);
  CHECK(rig.index[0][0] == Approx(1.0 + 0.15).epsilon(1e-12));
  CHECK(rig.index[0][1] == Approx(1.0 + 0.35).epsilon(1e-12));
}

TEST_CASE("absolute encoder reads actual plus offset") {
  AxisConfig a = cam(100, 200);
  a.actual_position_mm = 7;
  a.absolute_offset_mm = 100;
  Rig rig(one_axis(a));
  rig.move_to(0, 5, 50, 500);
  CHECK(rig.sim.inputs().axes[0].absolute_valid);
  CHECK(rig.sim.inputs().axes[0].absolute_position_mm == Approx(112));
  rig.sim.lose_steps(0, -1);
  rig.step(0, stop_command(500));
  CHECK(rig.sim.inputs().axes[0].absolute_position_mm == Approx(111));
}

TEST_CASE("against a mechanical stop the encoder reads where the carriage is held while the steps go on") {
  AxisConfig a = cam(100, 200);
  a.actual_position_mm = 10;
  a.hard_stop_max_mm = 20;
  a.absolute_offset_mm = 5;
  Rig rig(one_axis(a));
  rig.run(0, velocity_command(100, 0), 300);  // motor 30 mm on, carriage held after 10
  CHECK(rig.motor(0) == Approx(30));
  CHECK(rig.sim.inputs().axes[0].absolute_position_mm == Approx(25));  // the stop, plus the offset
  rig.run(0, velocity_command(100, 0), 100);
  CHECK(rig.sim.inputs().axes[0].absolute_position_mm == Approx(25));
}

TEST_CASE("the encoder counts in steps of its resolution, with seeded noise on each reading") {
  AxisConfig a = cam(100, 200);
  a.actual_position_mm = 7.0004;
  a.encoder_resolution_mm = 0.001;
  Rig exact(one_axis(a));
  CHECK(exact.sim.inputs().axes[0].absolute_position_mm == Approx(7.000).margin(1e-12));
  a.encoder_resolution_mm = 0;
  a.encoder_noise_mm = 0.002;
  auto readings = [&](std::uint64_t seed) {
    MachineConfig c = one_axis(a);
    c.seed = seed;
    Rig rig(c);
    std::vector<double> xs;
    for (int k = 0; k < 2000; ++k) {
      rig.step(0, stop_command(500));
      xs.push_back(rig.sim.inputs().axes[0].absolute_position_mm - 7.0004);
    }
    return xs;
  };
  const auto first = readings(11);
  CHECK(first == readings(11));  // the seed repeats it exactly
  CHECK(first != readings(12));
  CHECK(stddev(first) == Approx(0.002).epsilon(0.1));
  SECTION("an exact encoder draws nothing: the switch's noise stays as it was") {
    a.encoder_noise_mm = 0;
    a.noise_mm = 0.01;
    MachineConfig c = one_axis(a);
    a.encoder_noise_mm = 0.002;
    MachineConfig noisy = one_axis(a);
    Rig quiet(c), loud(noisy);
    quiet.move_to(0, 150, 50, 500);
    loud.move_to(0, 150, 50, 500);
    CHECK(quiet.sensor[0].size() == loud.sensor[0].size());
    for (std::size_t e = 0; e < std::min(quiet.sensor[0].size(), loud.sensor[0].size()); ++e)
      CHECK(quiet.sensor[0][e].time_s == loud.sensor[0][e].time_s);
  }
}

TEST_CASE("a reversed encoder (sim fault encoder_reversed) counts against the carriage") {
  AxisConfig a = cam(100, 200);
  a.actual_position_mm = 7;
  a.absolute_offset_mm = 100;
  a.fault = Fault::encoder_reversed;
  Rig rig(one_axis(a));
  CHECK(rig.sim.inputs().axes[0].absolute_position_mm == Approx(93));
  rig.move_to(0, 5, 50, 500);  // the carriage 5 mm up
  CHECK(rig.sim.inputs().axes[0].absolute_position_mm == Approx(88));
}

TEST_CASE("lose_steps shifts the carriage without the motor knowing") {
  Rig rig(one_axis(cam(5, 50)));
  rig.move_to(0, 2, 50, 500);
  rig.sim.lose_steps(0, 1.5);
  CHECK(rig.sim.actual_position_mm(0) == Approx(3.5));
  CHECK(rig.motor(0) == 2);
  rig.move_to(0, 4, 50, 500);  // carriage reaches 5.5
  const auto edge = rig.sim.last_edge(0);
  REQUIRE(edge);
  CHECK(edge->actual_mm == Approx(5));
  CHECK(edge->motor_mm == Approx(3.5));
  CHECK(rig.sim.actual_position_mm(0) == Approx(5.5));
  CHECK(rig.sim.axis_config(0).actual_position_mm == Approx(5.5));
}

TEST_CASE("place is refused while the axis moves and takes effect at the next period") {
  Rig rig(one_axis(cam(5, 50)));
  rig.run(0, velocity_command(20, 1000), 20);
  CHECK(rig.sim.moving(0));
  CHECK_FALSE(rig.sim.place(0, 10));
  rig.move_to(0, 1, 20, 1000);
  CHECK_FALSE(rig.sim.moving(0));
  REQUIRE(rig.sim.place(0, 10));
  CHECK(rig.sim.actual_position_mm(0) == 10);
  rig.sensor[0].clear();
  rig.step(0, stop_command(1000));
  REQUIRE(rig.sensor[0].size() == 1);  // jumped into the cam: the edge is at the period start
  CHECK(rig.sim.inputs().axes[0].sensor_edges.time_s[0] == 0.0);
  CHECK(rig.sim.inputs().axes[0].sensor_level);
  rig.move_to(0, 2, 20, 1000);
  CHECK(rig.sim.actual_position_mm(0) == Approx(11));  // the motor's moves now start from 10
}

TEST_CASE("commutator routes the slave's sensor to the master's input") {
  MachineConfig c;
  c.axes[0] = cam(5, 50);   // master carriage at 0: its switch is inactive
  c.axes[1] = cam(-50, 3);  // slave carriage at 0: its switch is active
  for (std::size_t i = 2; i < kAxisCount; ++i) c.axes[i] = cam(1, -1);
  c.commutator_slave[0] = 1;
  Rig rig(c);
  rig.step(0, stop_command(100));
  CHECK_FALSE(rig.sim.inputs().axes[0].sensor_level);
  rig.out.axes[0].commutator_output = true;
  rig.step(0, stop_command(100));
  CHECK(rig.sim.inputs().axes[0].sensor_level);
  CHECK(rig.sim.inputs().axes[0].sensor_edges.count == 0);  // a switch-over has no edge time
  CHECK(rig.sim.inputs().axes[1].sensor_level);
  // The master's output now moves only the slave (as when aligning): its edge
  // shows on the master's input.
  rig.sensor[0].clear();
  rig.run(0, velocity_command(10, 0), 400);
  REQUIRE(rig.sensor[0].size() == 1);
  CHECK(rig.sensor[0][0].time_s == Approx(0.002 + 0.3).epsilon(1e-12));
  CHECK_FALSE(rig.sensor[0][0].level);
  CHECK(rig.sim.actual_position_mm(0) == 0);
  CHECK(rig.sim.actual_position_mm(1) == Approx(4));
  rig.out.axes[0].commutator_output = false;
  rig.step(0, stop_command(100));
  CHECK_FALSE(rig.sim.inputs().axes[0].sensor_level);
}

namespace {

// X master, Y its external-commutator slave; no cams unless a test sets them.
MachineConfig commutator_machine(double x_mm, double y_mm) {
  MachineConfig c;
  for (auto& a : c.axes) a = cam(1, -1);
  c.axes[0].actual_position_mm = x_mm;
  c.axes[1].actual_position_mm = y_mm;
  c.commutator_slave[0] = 1;
  return c;
}

}  // namespace

TEST_CASE("commutator wiring: the master's output moves both carriages, with the commutator on only the slave's") {
  Rig rig(commutator_machine(10, 20));
  // The slave has no output of its own: whatever the engine leaves in it is ignored.
  rig.out.axes[1].motion = velocity_command(-50, 0);
  rig.run(0, velocity_command(10, 0), 100);  // 1 mm
  CHECK(rig.sim.actual_position_mm(0) == Approx(11).margin(1e-9));
  CHECK(rig.sim.actual_position_mm(1) == Approx(21).margin(1e-9));
  CHECK(rig.sim.moving(0));
  CHECK(rig.sim.moving(1));
  CHECK(rig.sim.driving_output(0) == 0);
  CHECK(rig.sim.driving_output(1) == 0);

  rig.out.axes[0].commutator_output = true;
  rig.run(0, velocity_command(10, 0), 200);  // 2 mm more on the output
  CHECK(rig.sim.actual_position_mm(0) == Approx(11).margin(1e-9));
  CHECK(rig.sim.actual_position_mm(1) == Approx(23).margin(1e-9));
  CHECK_FALSE(rig.sim.moving(0));
  CHECK(rig.sim.moving(1));

  rig.out.axes[0].commutator_output = false;
  rig.move_to(0, 0, 10, 1000);  // back 3 mm on the output: both carriages
  CHECK(rig.sim.actual_position_mm(0) == Approx(8).margin(1e-9));
  CHECK(rig.sim.actual_position_mm(1) == Approx(20).margin(1e-9));
  CHECK_FALSE(rig.sim.moving(0));
  CHECK_FALSE(rig.sim.moving(1));
}

TEST_CASE("commutator wiring: each carriage stops at its own mechanical stop and its own drive fault") {
  MachineConfig c = commutator_machine(10, 20);
  c.axes[0].hard_stop_max_mm = 12;
  Rig rig(c);
  rig.run(0, velocity_command(10, 0), 500);  // 5 mm on the output
  CHECK(rig.sim.actual_position_mm(0) == Approx(12).margin(1e-9));  // pushed against its stop
  CHECK(rig.sim.at_hard_stop(0));
  CHECK(rig.sim.actual_position_mm(1) == Approx(25).margin(1e-9));

  AxisConfig y = rig.sim.axis_config(1);
  y.fault = Fault::drive_fault;
  rig.sim.set_axis_config(1, y);
  rig.run(0, velocity_command(-10, 0), 300);  // 3 mm back: the slave's drive does not follow
  CHECK(rig.sim.actual_position_mm(0) == Approx(9).margin(1e-9));  // steps lost at the stop stay lost
  CHECK(rig.sim.actual_position_mm(1) == Approx(25).margin(1e-9));
  CHECK(rig.sim.inputs().axes[1].drive_fault);
  CHECK_FALSE(rig.sim.inputs().axes[0].drive_fault);
}

TEST_CASE("commutator wiring: a slave's edge records its own carriage and the master output's position") {
  MachineConfig c = commutator_machine(10, 20);
  c.axes[1].sensor_min_mm = 22.5;  // the slave's cam
  c.axes[1].sensor_max_mm = 100;
  Rig rig(c);
  rig.run(0, velocity_command(10, 0), 100);  // both +1 mm: output at 1
  rig.out.axes[0].commutator_output = true;
  rig.run(0, velocity_command(10, 0), 200);  // the slave alone reaches 23
  const auto edge = rig.sim.last_edge(1);
  REQUIRE(edge);
  CHECK(edge->to_active);
  CHECK(edge->actual_mm == Approx(22.5));
  CHECK(edge->output == 0);
  CHECK(edge->motor_mm == Approx(2.5));  // the output's count at that instant (slave slip 20)
  CHECK(edge->time_s == Approx(0.25).epsilon(1e-9));
  CHECK_FALSE(rig.sim.last_edge(0));  // nothing on the master's own switch
  CHECK(rig.sim.inputs().axes[0].sensor_level);  // the master's input shows the slave's switch
}

TEST_CASE("commutator wiring: in_motion tells which carriage the next outputs move") {
  Rig rig(commutator_machine(10, 20));
  Outputs next{};
  next.axes[0].motion = velocity_command(10, 100);
  CHECK(rig.sim.in_motion(0, next));
  CHECK(rig.sim.in_motion(1, next));
  CHECK_FALSE(rig.sim.in_motion(2, next));
  next.axes[0].commutator_output = true;
  CHECK_FALSE(rig.sim.in_motion(0, next));
  CHECK(rig.sim.in_motion(1, next));
  next = Outputs{};
  next.axes[1].motion = velocity_command(10, 100);  // the slave's own output does not exist
  CHECK_FALSE(rig.sim.in_motion(1, next));
}

TEST_CASE("commutator wiring follows set_commutator_slave at run time") {
  Rig rig(commutator_machine(10, 20));
  rig.sim.set_commutator_slave(0, -1);
  CHECK(rig.sim.driving_output(1) == 1);
  rig.run(0, velocity_command(10, 0), 100);
  CHECK(rig.sim.actual_position_mm(0) == Approx(11).margin(1e-9));
  CHECK(rig.sim.actual_position_mm(1) == Approx(20).margin(1e-9));  // unwired: only its own output moves it
  rig.run(1, velocity_command(10, 0), 100);
  CHECK(rig.sim.actual_position_mm(1) == Approx(21).margin(1e-9));
  rig.sim.set_commutator_slave(0, 1);
  rig.out.axes[1].motion = stop_command(0);
  rig.run(0, velocity_command(10, 0), 100);
  CHECK(rig.sim.actual_position_mm(0) == Approx(13).margin(1e-9));
  CHECK(rig.sim.actual_position_mm(1) == Approx(22).margin(1e-9));
}

TEST_CASE("global inputs follow the setters") {
  Simulator sim(MachineConfig{});
  sim.set_estop(true);
  sim.set_start_button(true);
  sim.set_homing_permit(true);
  sim.advance(Outputs{}, kDt_s);
  CHECK(sim.inputs().estop);
  CHECK(sim.inputs().start_button);
  CHECK(sim.inputs().homing_permit);
  CHECK_FALSE(sim.inputs().commands.home_all);
  sim.set_estop(false);
  CHECK_FALSE(sim.inputs().estop);
}
