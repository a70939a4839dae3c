// The simulator behind the engine's machine interface (homing/sim/simulator_io.hpp):
// the runtime reaches the simulator's extra controls only through the backend.
#include <catch2/catch.hpp>

#include "homing/gantry.hpp"
#include "homing/machine_io.hpp"
#include "homing/sim/simulator_io.hpp"

using namespace homing;
using namespace homing::sim;

namespace {

// A machine with nothing but the interface's defaults, like real hardware.
struct BareMachine final : MachineIo {
  void advance(const Outputs&, double) override {}
  Inputs read() override { return {}; }
};

MachineConfig machine() {
  MachineConfig m;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    m.axes[a].actual_position_mm = 50;
    m.axes[a].hard_stop_min_mm = 0;
    m.axes[a].hard_stop_max_mm = 100;
    m.axes[a].sensor_min_mm = 10;
    m.axes[a].sensor_max_mm = 20;
  }
  return m;
}

// Every axis homes on a switch: a gantry needs both sides to.
Settings switch_axes() {
  Settings s;
  for (auto& a : s.axes) a.mode = HomingMode::switch_release;
  return s;
}

Settings external_commutator_slave(Settings s, std::size_t slave, std::size_t master) {
  s.axes[slave].slave_of = static_cast<std::uint8_t>(master + 1);
  s.axes[slave].slave_mode = SlaveMode::external_commutator;
  return s;
}

}  // namespace

TEST_CASE("the simulator backend offers simulator controls and a machine without them offers none") {
  SimulatorIo sim(machine());
  BareMachine bare;
  CHECK(sim.simulator_controls() != nullptr);
  CHECK(bare.simulator_controls() == nullptr);
}

TEST_CASE("simulator controls change the machine the backend reads and show it in the view") {
  SimulatorIo io(machine());
  SimulatorControls& controls = *io.simulator_controls();
  REQUIRE(controls.place(1, 15));
  controls.set_estop(true);
  controls.set_start_button(true);
  controls.set_seed(42);
  io.advance(Outputs{}, 0.001);

  const SimulatorView view = controls.view();
  CHECK(view.axes[1].actual_position_mm == Approx(15));
  CHECK(view.config.axes[1].actual_position_mm == Approx(15));
  CHECK(view.axes[1].sensor);
  CHECK_FALSE(view.axes[0].sensor);
  CHECK(view.estop);
  CHECK(view.start_button);
  CHECK(view.config.seed == 42);
  CHECK(view.time_s == Approx(0.001));
  const Inputs in = io.read();
  CHECK(in.estop);
  CHECK(in.start_button);
  CHECK(in.axes[1].sensor_level);
}

TEST_CASE("external-commutator slaves in the settings are wired to their master and only the first of two on one master") {
  const Settings own = switch_axes();
  CHECK(commutator_wiring(own) == std::array<int, kAxisCount>{-1, -1, -1, -1, -1, -1});

  Settings s = external_commutator_slave(own, 1, 0);  // Y on X's output
  s = external_commutator_slave(s, 3, 0);             // a second slave on X: not wired
  s.axes[4].slave_of = 3;                             // A follows Z on its own output: no commutator
  CHECK(commutator_wiring(s) == std::array<int, kAxisCount>{1, -1, -1, -1, -1, -1});
}

TEST_CASE("a disabled axis named as a commutator slave is not wired to its master") {
  Settings s = external_commutator_slave(switch_axes(), 1, 0);  // Y on X's output
  REQUIRE(commutator_wiring(s)[0] == 1);
  s.axes[1].mode = HomingMode::disabled;
  CHECK_FALSE(is_commutator_slave(s, 1));
  CHECK(commutator_wiring(s) == std::array<int, kAxisCount>{-1, -1, -1, -1, -1, -1});
}

TEST_CASE("the simulated commutators follow the settings when they change") {
  SimulatorIo io(machine());
  SimulatorControls& controls = *io.simulator_controls();
  controls.follow_settings(external_commutator_slave(switch_axes(), 2, 1));  // Z on Y's output
  CHECK(controls.view().config.commutator_slave[1] == 2);
  CHECK(controls.view().axes[2].driven_by == 2);  // master Y is output 1: shown as 1 + 1
  CHECK(controls.view().axes[1].driven_by == 0);

  controls.follow_settings(switch_axes());
  CHECK(controls.view().config.commutator_slave[1] == -1);
  CHECK(controls.view().axes[2].driven_by == 0);
}
