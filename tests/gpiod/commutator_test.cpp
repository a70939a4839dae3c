// An external-commutator gantry on GPIO: the slave axis has no step/dir or
// home lines of its own, the master's commutator line follows the engine's
// commutator output, and the wiring is checked against the settings.
#include <catch2/catch.hpp>
#include <toml++/toml.h>

#include "backend_fixture.hpp"

using namespace homing::gpiod;
using homing::Outputs;

namespace {

constexpr std::int64_t kMs = 1'000'000;

// X drives both gantry motors through a commutator; Y (the slave) has only
// its own drive's enable and alarm lines; Z is not wired at all.
constexpr const char* kGantry = R"(
[gpiod]
chip = "gpiochip0"
tick_us = 20

[gpiod.axes.X]
steps_per_unit = 400
step = 23
dir = 24
home = 4
commutator = 20

[gpiod.axes.Y]
enable = 21
drive_fault = 26
)";

std::string error_of(const char* text) {
  auto c = parse_config(toml::parse(text), "cabinet.toml");
  return c ? std::string("(accepted)") : c.error();
}

homing::AxisSettings switch_axis() {
  homing::AxisSettings s;
  s.mode = homing::HomingMode::switch_release;
  return s;
}

// X homes on a switch, Y is its external-commutator slave, the rest disabled.
homing::Settings gantry_settings() {
  homing::Settings s;
  s.axes[0] = switch_axis();
  s.axes[1] = switch_axis();
  s.axes[1].slave_of = 1;
  s.axes[1].slave_mode = homing::SlaveMode::external_commutator;
  return s;
}

}  // namespace

TEST_CASE("config: an axis without step and dir is accepted, half a step/dir pair is not") {
  const BackendConfig c = fixture::config(kGantry);
  CHECK(c.axes[0].has_output());
  CHECK(c.axes[1].configured);
  CHECK_FALSE(c.axes[1].has_output());
  CHECK_FALSE(c.axes[1].home);
  CHECK_FALSE(c.axes[2].configured);
  CHECK_THAT(error_of("[gpiod]\nchip = \"gpiochip0\"\n[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\ndir = 24\n"
                      "[gpiod.axes.Y]\ndir = 3\n"),
             Catch::Contains("[gpiod.axes.Y] needs both 'step' and 'dir'"));
  CHECK_THAT(error_of("[gpiod]\nchip = \"gpiochip0\"\n[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\ndir = 24\n"
                      "[gpiod.axes.Y]\ncommutator = 3\n"),
             Catch::Contains("[gpiod.axes.Y] has no step/dir output, so no 'commutator' line either"));
}

TEST_CASE("the master's commutator line follows the engine's commutator output and the slave has no pulses") {
  fixture::Backend b(fixture::config(kGantry));
  REQUIRE(b.io->generator(0) != nullptr);
  CHECK(b.io->generator(1) == nullptr);
  CHECK_FALSE(b.chip->value("X.commutator"));
  b.period(Outputs{}, 0);
  b.period(Outputs{}, kMs);
  Outputs out{};
  out.axes[0].enable = out.axes[1].enable = true;
  out.axes[0].motion = homing::velocity_command(5, 0);  // 2 steps per ms on X's output
  out.axes[1].motion = homing::velocity_command(-50, 0);  // the slave has no output: nothing to play
  out.axes[0].commutator_output = true;
  b.period(out, kMs);
  CHECK(b.chip->value("X.commutator"));
  CHECK(b.chip->value("Y.enable"));
  CHECK(b.io->generator(0)->position_steps() == 2);
  out.axes[0].motor = homing::MotionState{0.005, 5};
  out.axes[0].commutator_output = false;
  b.period(out, kMs);
  CHECK_FALSE(b.chip->value("X.commutator"));
  CHECK(b.io->generator(0)->position_steps() == 4);
  // The slave's own drive alarm is still read.
  b.chip->set_level_silently("Y.drive_fault", true);
  CHECK(b.period(out, kMs).axes[1].drive_fault);
  b.io->shutdown();
  CHECK_FALSE(b.chip->value("X.commutator"));
  CHECK_FALSE(b.chip->value("Y.enable"));
}

TEST_CASE("wiring check: an external-commutator slave needs no lines of its own, only its master's output and commutator") {
  const BackendConfig wiring = fixture::config(kGantry);
  CHECK_FALSE(check_wiring(wiring, gantry_settings()));

  BackendConfig no_commutator = wiring;
  no_commutator.axes[0].commutator.reset();
  const auto problem = check_wiring(no_commutator, gantry_settings());
  REQUIRE(problem);
  CHECK_THAT(*problem, Catch::Contains("Y is an external-commutator slave of X") &&
                           Catch::Contains("[gpiod.axes.X] has no 'commutator' output line"));
}

TEST_CASE("wiring check: an axis the settings can move needs its own step/dir, and a home line to home on a switch") {
  const BackendConfig wiring = fixture::config(kGantry);
  homing::Settings s = gantry_settings();
  s.axes[1].slave_mode = homing::SlaveMode::own_output;  // Y would need its own motor output now
  auto problem = check_wiring(wiring, s);
  REQUIRE(problem);
  CHECK_THAT(*problem, Catch::Contains("axis.y.mode is 2") && Catch::Contains("[gpiod.axes.Y] has no step/dir output") &&
                           Catch::Contains("axis.y.mode = 0 (disabled)"));

  s = gantry_settings();
  s.axes[2] = switch_axis();  // Z is not wired at all
  problem = check_wiring(wiring, s);
  REQUIRE(problem);
  CHECK_THAT(*problem, Catch::Contains("[gpiod.axes.Z] has no step/dir output"));
  s.axes[2].mode = homing::HomingMode::disabled;  // an axis that never moves needs nothing
  CHECK_FALSE(check_wiring(wiring, s));

  BackendConfig no_home = wiring;
  no_home.axes[0].home.reset();
  problem = check_wiring(no_home, gantry_settings());
  REQUIRE(problem);
  CHECK_THAT(*problem, Catch::Contains("axis.x.mode 2 homes on a switch but [gpiod.axes.X] has no 'home' line"));
  homing::Settings manual = gantry_settings();
  manual.axes[0].mode = homing::HomingMode::manual;
  manual.axes[1] = homing::AxisSettings{};
  CHECK_FALSE(check_wiring(no_home, manual));  // manual homing moves only by jog and move: no switch needed
}
