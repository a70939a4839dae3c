// docs/operating.md "homingd options": SIGTERM "stops all motion (controlled
// deceleration)". The real daemon moves an axis at a known speed and
// acceleration over Modbus/TCP, gets SIGTERM, and its log's account of the
// stop must show the axis braking at its acceleration: v²/2a of travel in
// v/a of machine time, neither an instant stop nor none.
#include <catch2/catch.hpp>

#include <cstdio>
#include <regex>

#include "daemon.hpp"
#include "homing/phases.hpp"
#include "homing/settings.hpp"

using namespace e2e;

namespace {

struct LoggedStop {
  double velocity = 0, from = 0, rest = 0, distance = 0, seconds = 0;
};

// The daemon's "stop: <axis> decelerated from ..." line for one axis.
std::optional<LoggedStop> logged_stop(const std::string& log, char axis) {
  const std::regex line(std::string("stop: ") + axis +
                        R"( decelerated from (-?[0-9.]+) \S+/s at (-?[0-9.]+) \S+ to rest at (-?[0-9.]+) \S+ \(([0-9.]+) \S+ in ([0-9.]+) s\))");
  std::smatch m;
  if (!std::regex_search(log, m, line)) return std::nullopt;
  return LoggedStop{std::stod(m[1]), std::stod(m[2]), std::stod(m[3]), std::stod(m[4]), std::stod(m[5])};
}

void stop_with_sigterm(Daemon& d) {
  const auto st = d.stop(SIGTERM, 30s);
  REQUIRE(st);
  CHECK(WIFEXITED(*st));
  CHECK(WEXITSTATUS(*st) == 0);
}

}  // namespace

TEST_CASE("SIGTERM during a jog brakes the axis at its acceleration before homingd exits") {
  constexpr double kFeed = 6000;  // mm/min: 100 mm/s
  constexpr double kAccel = 500;  // mm/s²: stops in 10 mm, 0.2 s
  Daemon d({.time_scale = 1});
  Client c = Client::tcp(d.port());
  c.set("global.allowed_without_homing", static_cast<int>(homing::AllowedWithoutHoming::all));
  c.set("axis.y.jog_feedrate", static_cast<std::int64_t>(kFeed));
  c.set("axis.y.acceleration", static_cast<std::int64_t>(kAccel));
  REQUIRE(c.write("cmd.jog_plus.y", 1) == 0);
  // At full speed, so the speed at the signal is known.
  REQUIRE(wait_until([&] { return c.read_mm("axis.y.velocity") >= kFeed / 60 - 0.01; }, 10s));
  const double before = c.read_mm("axis.y.position");
  stop_with_sigterm(d);

  const std::string log = d.log();
  INFO(log);
  const auto y = logged_stop(log, 'Y');
  REQUIRE(y);
  const double v = kFeed / 60;
  CHECK(y->velocity == Approx(v).margin(0.01));
  CHECK(y->from >= before);
  CHECK(y->rest - y->from == Approx(y->distance).margin(0.002));
  // v²/2a: one control period of reaction at full speed (0.1 mm) is the
  // only slack; an instant stop travels nothing, a sharper one less.
  CHECK(y->distance == Approx(v * v / (2 * kAccel)).margin(0.15));
  // Machine time, counted in whole control periods: a late period adds to it.
  CHECK(y->seconds >= 0.95 * v / kAccel);
  CHECK(y->seconds <= v / kAccel + 0.1);
  CHECK_FALSE(logged_stop(log, 'X'));  // nothing else moved
  CHECK(log.find("still moving") == std::string::npos);
}

TEST_CASE("SIGTERM during homing brakes the seeking axis at its acceleration before homingd exits") {
  Daemon d({.time_scale = 1});
  Client c = Client::tcp(d.port());
  c.set("axis.z.seek_feedrate", 3000);  // mm/min: 50 mm/s
  c.set("axis.z.acceleration", 400);    // mm/s²: stops in 3.125 mm, 0.125 s
  c.set("axis.z.max_stop_distance", um(10));
  c.set("sim.z.actual_position", um(200));  // far from its sensor: still seeking at the signal
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return std::abs(c.read_mm("axis.z.velocity")) >= 50 - 0.01; }, 10s));
  REQUIRE(c.read("axis.z.phase") == static_cast<int>(homing::Phase::seek));
  stop_with_sigterm(d);

  const std::string log = d.log();
  INFO(log);
  const auto z = logged_stop(log, 'Z');
  REQUIRE(z);
  CHECK(std::abs(z->velocity) == Approx(50).margin(0.01));
  CHECK(z->distance == Approx(50.0 * 50 / (2 * 400)).margin(0.1));
  CHECK(z->seconds >= 0.95 * 50.0 / 400);
  CHECK(z->seconds <= 50.0 / 400 + 0.1);
  CHECK(log.find("still moving") == std::string::npos);
}
