// The [gpiod] table: every mistake is named with the file, section and key.
#include <catch2/catch.hpp>
#include <toml++/toml.h>

#include "backend_fixture.hpp"

using namespace homing::gpiod;

namespace {
std::string error_of(const char* text) {
  auto c = parse_config(toml::parse(text), "cabinet.toml");
  return c ? std::string("(accepted)") : c.error();
}
}  // namespace

TEST_CASE("the README example is accepted: offsets, names, active-low, bias") {
  const BackendConfig c = fixture::config();
  const AxisLines& x = c.axes[0];
  REQUIRE(x.configured);
  CHECK(x.steps_per_unit == 400);
  CHECK(std::get<unsigned>(x.step->line) == 23);
  CHECK(x.step->chip == "gpiochip0");
  CHECK(x.step->role == "X.step");
  CHECK(x.enable->active_low);
  CHECK(x.home->bias == Bias::pull_up);
  CHECK(std::get<std::string>(c.start_button->line) == "START");
  CHECK(c.estop->active_low);
  CHECK_FALSE(c.axes[1].configured);
  CHECK(c.tick_us == 20);
}

TEST_CASE("config mistakes name the file, the section and the key") {
  CHECK_THAT(error_of(""), Catch::Contains("cabinet.toml: no [gpiod] table"));
  CHECK_THAT(error_of("[gpiod]\nchip = \"gpiochip0\""), Catch::Contains("configures no axis"));
  CHECK_THAT(error_of("[gpiod]\nchip = \"gpiochip0\"\n[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\n"),
             Catch::Contains("[gpiod.axes.X] needs both 'step' and 'dir'"));
  CHECK_THAT(error_of("[gpiod]\nchip = \"gpiochip0\"\n[gpiod.axes.X]\nstep = 23\ndir = 24\n"),
             Catch::Contains("[gpiod.axes.X] needs steps_per_unit"));
  CHECK_THAT(error_of("[gpiod]\nchip = \"gpiochip0\"\n[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\ndir = 24\nhom = 4\n"),
             Catch::Contains("[gpiod.axes.X] unknown key 'hom'"));
  CHECK_THAT(error_of("[gpiod]\nchip = \"gpiochip0\"\n[gpiod.axes.Q]\nsteps_per_unit = 1\nstep = 1\ndir = 2\n"),
             Catch::Contains("[gpiod.axes.Q] is not an axis"));
  CHECK_THAT(error_of("[gpiod]\n[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\ndir = 24\n"),
             Catch::Contains("[gpiod.axes.X] dir: a line offset needs a chip"));
  CHECK_THAT(error_of("[gpiod]\nchip = \"gpiochip0\"\n[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\ndir = 23\n"),
             Catch::Contains("X.step (gpiochip0 line 23) and X.dir (gpiochip0 line 23) are on the same line"));
  CHECK_THAT(error_of("[gpiod]\nchip = \"gpiochip0\"\nestop = { line = 3, bias = \"up\" }\n"
                      "[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\ndir = 24\n"),
             Catch::Contains("[gpiod] estop: bias \"up\" is not one of"));
  CHECK_THAT(error_of("[gpiod]\nchip = \"gpiochip0\"\ntick_us = 0\n[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\ndir = 24\n"),
             Catch::Contains("[gpiod] tick_us must be an integer"));
  CHECK_THAT(error_of("[gpiod]\nchip = \"gpiochip0\"\nlamp = 5\n[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\ndir = 24\n"),
             Catch::Contains("[gpiod] unknown key 'lamp'"));
}

TEST_CASE("load_config: no file, and a TOML syntax error with its line") {
  CHECK_THAT(load_config("").error(), Catch::Contains("--config FILE"));
  const std::string path = "gpiod_config_test_bad.toml";
  { std::FILE* f = std::fopen(path.c_str(), "w"); std::fputs("[gpiod]\nchip = \n", f); std::fclose(f); }
  CHECK_THAT(load_config(path).error(), Catch::Contains(path + ": line 2"));
  std::remove(path.c_str());
}
