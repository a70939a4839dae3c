// homingd --backend gpiod on a machine without the configured GPIO: the start
// fails with one line naming the problem (there is no GPIO chip on CI).
#include <catch2/catch.hpp>

#include <fstream>

#include "daemon.hpp"

using namespace e2e;

namespace {

std::string last_line(const std::string& text) {
  std::string t = text;
  while (!t.empty() && t.back() == '\n') t.pop_back();
  const auto nl = t.rfind('\n');
  return nl == std::string::npos ? t : t.substr(nl + 1);
}

}  // namespace

TEST_CASE("homingd --backend gpiod with a chip that does not exist names the chip and the line") {
  TempDir dir;
  const std::string config = dir.file("cabinet.toml");
  // X, Y and Z: the axes the default settings home.
  std::ofstream(config) << "[gpiod]\nchip = \"gpiochip9\"\n[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\ndir = 24\n"
                           "home = 4\n[gpiod.axes.Y]\nsteps_per_unit = 400\nstep = 5\ndir = 6\nhome = 7\n"
                           "[gpiod.axes.Z]\nsteps_per_unit = 400\nstep = 8\ndir = 9\nhome = 10\n";
  const RunResult r = run_program({homingd_path(), "--backend", "gpiod", "--config", config, "--db",
                                   dir.file("s.db"), "--tcp", "127.0.0.1:" + std::to_string(free_port())},
                                  20s);
  CHECK(r.code() == 1);
  const std::string line = last_line(r.err);
  CHECK(line.find("gpiochip9") != std::string::npos);
  CHECK(line.find("X.step") != std::string::npos);
  CHECK(r.out.find("listening") == std::string::npos);
}

TEST_CASE("homingd --backend gpiod with a config mistake names the file, the section and the key") {
  TempDir dir;
  const std::string config = dir.file("cabinet.toml");
  // dir is missing for X: every homing axis needs step, dir and steps_per_unit.
  std::ofstream(config) << "[gpiod]\nchip = \"gpiochip0\"\n[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\n";
  const RunResult r = run_program({homingd_path(), "--backend", "gpiod", "--config", config, "--db",
                                   dir.file("s.db"), "--tcp", "127.0.0.1:" + std::to_string(free_port())},
                                  20s);
  CHECK(r.code() != 0);
  const std::string line = last_line(r.err);
  CHECK(line.find("cabinet.toml") != std::string::npos);
  CHECK(line.find("dir") != std::string::npos);
  CHECK(r.out.find("listening") == std::string::npos);
}

TEST_CASE("homingd --backend gpiod refuses settings that move an axis with no step/dir lines, naming both") {
  TempDir dir;
  const std::string config = dir.file("cabinet.toml");
  // Only X is wired; the default settings home X, Y and Z. The check comes
  // before any line is requested (there is no chip here).
  std::ofstream(config) << "[gpiod]\nchip = \"gpiochip9\"\n[gpiod.axes.X]\nsteps_per_unit = 400\nstep = 23\ndir = 24\n"
                           "home = 4\n[gpiod.axes.Y]\nenable = 5\n";
  const RunResult r = run_program({homingd_path(), "--backend", "gpiod", "--config", config, "--db",
                                   dir.file("s.db"), "--tcp", "127.0.0.1:" + std::to_string(free_port())},
                                  20s);
  CHECK(r.code() == 1);
  const std::string line = last_line(r.err);
  CHECK(line.find("cabinet.toml") != std::string::npos);
  CHECK(line.find("axis.y.mode") != std::string::npos);
  CHECK(line.find("[gpiod.axes.Y] has no step/dir output") != std::string::npos);
  CHECK(r.out.find("listening") == std::string::npos);
}
