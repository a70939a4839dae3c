// homingctl against a real homingd (simulator backend, --time-scale 10): every
// command, text and --json, a refused write, a failing homing, exit codes.
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <cmath>

#include "tools_helpers.hpp"

using namespace tools_test;

TEST_CASE("homingctl status and get: one table, words, engineering units, --json") {
  Daemon d;
  // Everything allowed before homing (the default allows a slow jog only): nothing blocks motion.
  REQUIRE(ctl(d, {"set", "global.allowed_without_homing=all"}).code() == 0);
  auto r = ctl(d, {"status"});
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("switch_release") != std::string::npos);
  CHECK(r.out.find("state: not_homed") != std::string::npos);
  CHECK(r.out.find("blocking motion: nothing (free to move)") != std::string::npos);
  for (const char* axis : {"X ", "Y ", "Z ", "A ", "B ", "C "}) CHECK(r.out.find(std::string("\n") + axis) != std::string::npos);

  r = ctl(d, {"status", "--json"});
  auto j = json_of(r);
  CHECK(j["state"] == "not_homed");
  REQUIRE(j["axes"].size() == 6);
  CHECK(j["axes"][0]["axis"] == "x");
  CHECK(j["axes"][0]["mode"] == "switch_release");
  CHECK(j["axes"][0]["unit"] == "mm");
  CHECK(j["axes"][3]["unit"] == "deg");
  CHECK(j["interlocks"].empty());

  // The default: before homing, motion is limited and status says so.
  REQUIRE(ctl(d, {"set", "global.allowed_without_homing=jog_reduced"}).code() == 0);
  r = ctl(d, {"status"});
  CHECK(r.out.find("blocking motion: not homed (motion limited)") != std::string::npos);

  r = ctl(d, {"get", "axis.x.seek_feedrate", "axis.x.pull_off", "axis.x.mode", "sequence.step2", "sim.x.sensor_max"});
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("axis.x.seek_feedrate = 1000 mm/min\n") != std::string::npos);
  CHECK(r.out.find("axis.x.pull_off = 1 mm\n") != std::string::npos);
  CHECK(r.out.find("axis.x.mode = switch_release\n") != std::string::npos);
  CHECK(r.out.find("sequence.step2 = x+y\n") != std::string::npos);
  CHECK(r.out.find("sim.x.sensor_max = 0 mm\n") != std::string::npos);

  r = ctl(d, {"--json", "get", "axis.a.*"});
  j = json_of(r);
  CHECK(j["axis.a.mode"]["text"] == "disabled");
  CHECK(j["axis.a.pull_off"]["unit"] == "deg");
  CHECK(j["axis.a.pull_off"]["value"] == Approx(1.0));
  CHECK(j["axis.a.pull_off"]["raw"] == 1000);
}

TEST_CASE("homingctl set: engineering units and enum names, several values in one all-or-nothing write") {
  Daemon d;
  Client c = Client::tcp(d.port());
  auto r = ctl(d, {"set", "axis.x.mode=switch_reapproach", "axis.x.pull_off=2.5mm", "axis.x.home_position=-5",
                   "axis.x.latch_feedrate=80", "sequence.step1=z", "global.watchdog_ms=0"});
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("axis.x.pull_off: 1 mm -> 2.5 mm") != std::string::npos);
  CHECK(c.read("axis.x.mode") == 3);
  CHECK(c.read("axis.x.pull_off") == 2500);
  CHECK(c.read("axis.x.home_position") == -5000);
  CHECK(c.read("axis.x.latch_feedrate") == 80);

  // Settings that only work together, in several requests: staged in one edit
  // session and applied at its commit, in one transaction.
  r = ctl(d, {"set", "axis.y.seek_feedrate=12000", "axis.y.max_stop_distance=50", "axis.y.max_backoff=60"});
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(c.read("axis.y.seek_feedrate") == 12000);
  CHECK(c.read("axis.y.max_stop_distance") == 50000);
  CHECK(d.log().find("committed: 3 staged settings, 3 changed") != std::string::npos);
  CHECK(c.read("edit.state") == 0);

  // --dry-run writes nothing.
  r = ctl(d, {"set", "--dry-run", "axis.z.pull_off=3"});
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("axis.z.pull_off: 1 mm -> 3 mm") != std::string::npos);
  CHECK(c.read("axis.z.pull_off") == 1000);
}

TEST_CASE("homingctl set: a refused write says why, names the setting, and changes nothing") {
  Daemon d;
  Client c = Client::tcp(d.port());
  const auto before = holding_snapshot(c);

  // Cross-field: the stop distance at that feedrate exceeds max_stop_distance.
  auto r = ctl(d, {"set", "axis.x.seek_feedrate=20000", "axis.x.pull_off=2"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("max_stop_distance") != std::string::npos);
    CHECK(r.err.find("seek_feedrate") != std::string::npos);
    CHECK(r.err.find("nothing was written") != std::string::npos);
  }
  // Out of range, with what is accepted.
  r = ctl(d, {"set", "axis.x.seek_feedrate=70000"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("out of range") != std::string::npos);
    CHECK(r.err.find("60000 mm/min") != std::string::npos);
  }
  r = ctl(d, {"set", "axis.x.mode=sideways"});
  CHECK(r.code() == 1);
  CHECK(r.err.find("switch_reapproach") != std::string::npos);
  // Read-only.
  r = ctl(d, {"set", "axis.x.position=3"});
  CHECK(r.code() == 1);
  CHECK(r.err.find("read-only") != std::string::npos);
  // Without the local check the module's exception is put in words, with
  // the reason the module gives and the register it is about; the edit
  // session it ran in is discarded.
  r = ctl(d, {"set", "--no-check", "axis.x.seek_feedrate=20000", "axis.x.pull_off=2"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("refused the change at its commit: exception 03") != std::string::npos);
    CHECK(r.err.find("cannot work together") != std::string::npos);
    CHECK(r.err.find("(about axis.x.") != std::string::npos);
    CHECK(r.err.find("nothing was changed") != std::string::npos);
    CHECK(r.out.find("->") == std::string::npos);  // stdout records no change that did not happen
  }
  CHECK(d.log().find("discarded by its client (2 staged settings dropped)") != std::string::npos);
  CHECK(holding_snapshot(c) == before);

  // A simulator write refused by the module: its reason in words, naming the register.
  r = ctl(d, {"set", "sim.x.actual_position=2000"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("beyond its hard stops") != std::string::npos);
    CHECK(r.err.find("(about sim.x.actual_position)") != std::string::npos);
  }
  // During a homing cycle the module answers 06: said in words.
  c.set("sim.x.actual_position", um(400));
  c.set("sim.y.actual_position", um(400));
  c.set("sim.z.actual_position", um(400));
  r = ctl(d, {"home", "--no-wait"});
  REQUIRE(r.code() == 0);
  r = ctl(d, {"set", "axis.x.pull_off=2"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("a homing cycle is running: settings cannot change now") != std::string::npos);
    CHECK(r.out.find("axis.x.pull_off") == std::string::npos);
  }
  CHECK(ctl(d, {"abort"}).code() == 0);
}

TEST_CASE("homingctl usage errors exit 2, an unreachable module exits 3, --help exits 0") {
  CHECK(ctl_plain({}).code() == 2);
  CHECK(ctl_plain({"frobnicate"}).code() == 2);
  CHECK(ctl_plain({"set", "axis.x.pull_off"}).code() == 2);
  CHECK(ctl_plain({"get", "no.such.register"}).code() == 2);
  CHECK(ctl_plain({"jog", "x", "sideways"}).code() == 2);
  // set changes settings only: a command or host value written through it would act.
  for (const char* not_a_setting : {"cmd.home_axes=1", "host.heartbeat=5", "axis.x.target=10", "edit.command=1"}) {
    const auto refused = ctl_plain({"set", not_a_setting});
    SHOW(refused);
    CHECK(refused.code() == 2);
    CHECK(refused.err.find("is not a setting") != std::string::npos);
  }
  auto r = ctl_plain({"--help"});
  CHECK(r.code() == 0);
  for (const char* sub : {"status", "watch", "home", "abort", "reset", "jog", "move", "get", "set", "check", "export",
                          "import", "history", "trace", "health"})
    CHECK(r.out.find(sub) != std::string::npos);
  r = ctl_plain({"home", "--help"});
  CHECK(r.code() == 0);
  CHECK(r.out.find("--no-wait") != std::string::npos);
  r = ctl_plain({"--tcp", "127.0.0.1:" + std::to_string(free_port()), "status"});
  {
    SHOW(r);
    CHECK(r.code() == 3);
    CHECK(r.err.find("cannot connect") != std::string::npos);
  }
  // Without a port: the message names the one tried.
  r = ctl_plain({"--tcp", "127.0.0.1", "status"});
  CHECK(r.err.find("127.0.0.1:502") != std::string::npos);
  // .invalid never resolves (RFC 6761): the name is what is wrong, not the network.
  r = ctl_plain({"--tcp", "cabinet-7.invalid:1502", "status"});
  {
    SHOW(r);
    CHECK(r.code() == 3);
    CHECK(r.err.find("cannot resolve cabinet-7.invalid") != std::string::npos);
  }
  // A port that is not one is the user's mistake (it used to wrap round to another port).
  for (const char* address : {"127.0.0.1:70000", "127.0.0.1:0", "127.0.0.1:15x"}) {
    r = ctl_plain({"--tcp", address, "status"});
    SHOW(r);
    CHECK(r.code() == 2);
    CHECK(r.err.find(std::string("--tcp ") + address + ": expected HOST or HOST:PORT, PORT from 1 to 65535") !=
          std::string::npos);
  }
}

TEST_CASE("homingctl --tcp takes the module's host name as well as its address") {
  Daemon d;
  const auto r = ctl_plain({"--tcp", "localhost:" + std::to_string(d.port()), "get", "axis.x.pull_off"});
  SHOW(r);
  CHECK(r.code() == 0);
  CHECK(r.out.find("axis.x.pull_off") != std::string::npos);
}

TEST_CASE("homingctl home waits for the result, a failing homing exits 1 with the alarm text") {
  Daemon d;
  Client c = Client::tcp(d.port());
  auto r = ctl(d, {"set", "axis.x.pull_off=2", "axis.x.home_position=-5"});
  REQUIRE(r.code() == 0);
  r = ctl(d, {"home"});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
    CHECK(r.out.find("home all: done, X = -5.000 mm") != std::string::npos);
    // Progress while it waited, on stderr (stdout keeps the result line).
    CHECK(r.err.find("step 2: X seek") != std::string::npos);
    CHECK(r.out.find("step 2: X seek") == std::string::npos);
  }
  CHECK(c.read("axis.x.position") == -5000);
  CHECK(c.read_mm("sim.x.actual_position") == Approx(0.05 + 2.0).margin(0.02));

  r = ctl(d, {"--json", "home", "x"});
  auto j = json_of(r);
  CHECK(r.code() == 0);
  CHECK(j["ok"] == true);
  CHECK(j["positions"]["x"] == Approx(-5.0));

  // The sensor never switches: the seek runs out of travel.
  REQUIRE(ctl(d, {"set", "axis.x.max_seek_travel=60", "sim.x.fault=sensor_stuck_inactive"}).code() == 0);
  r = ctl(d, {"home", "x"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("X: home sensor not found within 60 mm of travel") != std::string::npos);
  }
  r = ctl(d, {"status"});
  CHECK(r.out.find("sensor_not_found") != std::string::npos);
  CHECK(r.out.find("alarm latched") != std::string::npos);

  // Refused while the alarm is latched, in words.
  r = ctl(d, {"home"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("an alarm is latched") != std::string::npos);
  }
  REQUIRE(ctl(d, {"set", "sim.x.fault=none"}).code() == 0);
  r = ctl(d, {"reset"});
  {
    SHOW(r);
    CHECK(r.code() == 0);
  }
  CHECK(ctl(d, {"home"}).code() == 0);

  // A drive fault: home refused, reset refused while the cause is present.
  REQUIRE(ctl(d, {"set", "sim.y.fault=drive_fault"}).code() == 0);
  r = ctl(d, {"home"});
  CHECK(r.code() == 1);
  CHECK(r.err.find("drive") != std::string::npos);
  r = ctl(d, {"reset"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("still present") != std::string::npos);
    CHECK(r.err.find("reset refused: reset refused") == std::string::npos);  // said once
  }
  REQUIRE(ctl(d, {"set", "sim.y.fault=none"}).code() == 0);
  CHECK(ctl(d, {"reset"}).code() == 0);
}

TEST_CASE("homingctl abort, reset, jog and move") {
  Daemon d;
  Client c = Client::tcp(d.port());
  for (const char* a : {"x", "y", "z"}) c.set(std::string("sim.") + a + ".actual_position", um(400));
  auto r = ctl(d, {"home", "--no-wait"});
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("not waiting") != std::string::npos);
  r = ctl(d, {"abort"});
  {
    SHOW(r);
    CHECK(r.code() == 0);
    CHECK(r.out.find("homingctl reset") != std::string::npos);
  }
  auto j = json_of(ctl(d, {"status", "--json"}));
  CHECK(j["state"] == "alarm");
  bool aborted = false;
  for (const auto& a : j["axes"])
    if (!a["alarm"].is_null() && a["alarm"]["name"] == "aborted") aborted = true;
  CHECK(aborted);
  CHECK(ctl(d, {"reset"}).code() == 0);
  REQUIRE(ctl(d, {"home"}).code() == 0);

  const double x0 = c.read_mm("axis.x.position");
  r = ctl(d, {"jog", "x", "+", "--ms", "300"});
  {
    SHOW(r);
    CHECK(r.code() == 0);
  }
  CHECK(c.read_mm("axis.x.position") > x0 + 1.0);
  CHECK(c.read("cmd.jog_plus.x") == 0);
  // Another client holds a jog button of X: homingctl presses nothing and says so.
  REQUIRE(c.write("cmd.jog_minus.x", 1) == 0);
  r = ctl(d, {"jog", "x", "+", "--ms", "300"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("cmd.jog_minus.x is held by another client") != std::string::npos);
  }
  CHECK(c.read("cmd.jog_plus.x") == 0);
  REQUIRE(c.write("cmd.jog_minus.x", 0) == 0);
  r = ctl(d, {"move", "x", "12.5"});
  {
    SHOW(r);
    CHECK(r.code() == 0);
    CHECK(r.out.find("move X to 12.5 mm: done, X = 12.500 mm") != std::string::npos);
  }
  CHECK(c.read("axis.x.position") == 12500);
  // Outside the soft limits: refused in words.
  REQUIRE(ctl(d, {"set", "axis.x.soft_limits_enable=on", "axis.x.soft_limit_max=100"}).code() == 0);
  r = ctl(d, {"move", "x", "150"});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("soft limits") != std::string::npos);
  }
}

TEST_CASE("homingctl watch shows the cycle with progress and exits with its result") {
  Daemon d;
  Client c = Client::tcp(d.port());
  for (const char* a : {"x", "y", "z"}) c.set(std::string("sim.") + a + ".actual_position", um(300));
  REQUIRE(ctl(d, {"home", "--no-wait"}).code() == 0);
  auto r = ctl(d, {"watch", "--interval-ms", "50", "--timeout-s", "60"});
  SHOW(r);
  CHECK(r.code() == 0);
  CHECK(r.out.find("homing cycle ended: homed") != std::string::npos);
  CHECK(r.out.find("[#") != std::string::npos);  // a progress bar
  CHECK(r.out.find(" seek ") != std::string::npos);

  // --json: one object per refresh; a failing cycle exits 1.
  c.set("sim.x.actual_position", um(300));
  REQUIRE(ctl(d, {"set", "sim.x.fault=sensor_stuck_inactive", "axis.x.max_seek_travel=100"}).code() == 0);
  REQUIRE(ctl(d, {"home", "--no-wait"}).code() == 0);
  r = ctl(d, {"watch", "--json", "--interval-ms", "50", "--timeout-s", "60"});
  CHECK(r.code() == 1);
  std::istringstream lines(r.out);
  std::string line, last;
  int n = 0;
  while (std::getline(lines, line))
    if (!line.empty()) {
      auto j = nlohmann::json::parse(line);
      CHECK(j.contains("axes"));
      last = line;
      ++n;
    }
  CHECK(n >= 2);
  auto j = nlohmann::json::parse(last);
  CHECK(j["cycle_ended"] == true);
  CHECK(j["axes"][0]["alarm"]["name"] == "sensor_not_found");
}

TEST_CASE("homingctl check: stop distance against its limit, cycle time, warnings") {
  Daemon d;
  auto r = ctl(d, {"check"});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
    CHECK(r.out.find("0.278 / 10 mm") != std::string::npos);
    CHECK(r.out.find("expected home-all cycle") != std::string::npos);
    CHECK(r.out.find("settings: ok") != std::string::npos);
  }
  REQUIRE(ctl(d, {"set", "axis.x.home_position=-1500", "axis.y.seek_feedrate=4000", "axis.y.acceleration=250",
                  "axis.y.max_stop_distance=10", "sim.z.sensor_min=-0.2"}).code() == 0);
  r = ctl(d, {"check"});
  {
    SHOW(r);
    CHECK(r.code() == 0);
    CHECK(r.out.find("home_position -1500 mm is outside the soft limits") != std::string::npos);
    CHECK(r.out.find("little margin") != std::string::npos);  // Y: 8.9 of 10 mm
    CHECK(r.out.find("shorter than the stop distance") != std::string::npos);  // Z: 0.2 mm cam
  }
  auto j = json_of(ctl(d, {"check", "--json"}));
  CHECK(j["ok"] == true);
  CHECK(j["axes"][0]["stop_distance"] == Approx(1000.0 * 1000.0 / 3600.0 / 1000.0).margin(1e-3));
  CHECK(j["axes"][1]["stop_distance"] == Approx(4000.0 * 4000.0 / 3600.0 / 500.0).margin(1e-3));
  CHECK(j["axes"][3]["enabled"] == false);
  CHECK(j["cycle_worst_s"].get<double>() > 30);
}

TEST_CASE("homingctl check shows what a method needs wired and how a hard-stop axis tells its stop") {
  Daemon d;
  REQUIRE(ctl(d, {"set", "axis.x.mode=hard_stop"}).code() == 0);
  auto r = ctl(d, {"check"});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
    CHECK(r.out.find("wiring: step, push, stall\n     stop told by: the drive's stall input") != std::string::npos);
    CHECK(r.out.find("wiring: step, home\n") != std::string::npos);  // Y: a switch
  }
  REQUIRE(ctl(d, {"set", "axis.x.stall_detect=following_error", "axis.x.max_following_error=0.3"}).code() == 0);
  r = ctl(d, {"check"});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
    CHECK(r.out.find("wiring: step, push, absolute\n     stop told by: following error above 0.3 mm (the encoder; "
                     "the stall input is not read)") != std::string::npos);
    CHECK(r.out.find("settings: ok") != std::string::npos);
  }
  auto j = json_of(ctl(d, {"check", "--json"}));
  CHECK(j["axes"][0]["stop_detection"] == "following_error");
  CHECK(j["axes"][0]["max_following_error"] == Approx(0.3));
  CHECK(j["axes"][0]["signals"] == nlohmann::json::array({"step", "push", "absolute"}));
  CHECK(j["axes"][1]["stop_detection"].is_null());
  // A limit within the encoder's noise: the engine's rule, in words.
  r = ctl(d, {"set", "axis.x.max_following_error=0.01"});
  SHOW(r);
  CHECK(r.code() != 0);
  CHECK(r.err.find("following_error") != std::string::npos);
}

TEST_CASE("homingctl history reads the daemon's database read-only while it runs") {
  Daemon d;
  REQUIRE(ctl(d, {"set", "axis.x.pull_off=1.5"}).code() == 0);
  REQUIRE(ctl(d, {"home"}).code() == 0);
  auto r = run_program({HOMINGCTL_PATH, "history", "--db", d.db()}, 30s);
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
    CHECK(r.out.find("axes XYZ") != std::string::npos);
    CHECK(r.out.find("axis.x.pull_off") != std::string::npos);
    CHECK(r.out.find("1 mm -> 1.5 mm") != std::string::npos);
  }
  auto j = json_of(run_program({HOMINGCTL_PATH, "history", "--json", "--db", d.db()}, 30s));
  REQUIRE(j["runs"].size() >= 1);
  CHECK(j["runs"][0]["result"] == "ok");
  CHECK(j["changes"][0]["name"] == "axis.x.pull_off");
  r = run_program({HOMINGCTL_PATH, "history", "--db", d.db() + ".missing"}, 30s);
  CHECK(r.code() == 1);
  CHECK(r.err.find("no such database") != std::string::npos);
}

TEST_CASE("homingctl status quotes the figure the alarm was raised with, not the axis position") {
  Daemon d;
  Client c = Client::tcp(d.port());
  // A gantry (Y slaved to X) whose slave sensor is dead: the racking guard
  // stops it and quotes the misalignment it saw.
  REQUIRE(ctl(d, {"set", "axis.z.mode=disabled", "sequence.step1=3", "sequence.step2=0", "axis.y.slave_of=1"}).code() == 0);
  REQUIRE(ctl(d, {"set", "sim.y.fault=sensor_stuck_inactive"}).code() == 0);
  auto r = ctl(d, {"home"});
  {
    SHOW(r);
    REQUIRE(r.code() == 1);
  }
  REQUIRE(c.read("axis.y.alarm") == static_cast<int>(homing::AlarmCode::misalignment));
  const double figure = c.read_mm("axis.y.alarm_value");
  const double position = c.read_mm("axis.y.position");
  REQUIRE(std::abs(figure - position) > 0.001);  // the two would read differently
  r = ctl(d, {"status"});
  SHOW(r);
  CHECK(r.out.find(fmt::format("racking by {:.3f} mm", figure)) != std::string::npos);
  CHECK(r.out.find(fmt::format("racking by {:.3f} mm", position)) == std::string::npos);
}

TEST_CASE("homingctl exits 3 when no device answers at its unit id (exception 0B), for reads and writes") {
  Daemon d;
  for (std::vector<std::string> args : {std::vector<std::string>{"--unit", "9", "status"},
                                        std::vector<std::string>{"--unit", "9", "get", "axis.x.pull_off"},
                                        std::vector<std::string>{"--unit", "9", "set", "axis.x.pull_off=2"},
                                        std::vector<std::string>{"--unit", "9", "abort"}}) {
    auto r = ctl(d, args);
    SHOW(r);
    CHECK(r.code() == 3);
    CHECK(r.err.find("exception 0B: no device answers at this unit id") != std::string::npos);
  }
  // Nothing was written through another unit id by mistake.
  Client c = Client::tcp(d.port());
  CHECK(c.read_mm("axis.x.pull_off") != Approx(2.0));
}

TEST_CASE("homingctl health: the last cycle's switch figures per axis, and the index warning with its fix") {
  Daemon d;
  auto r = ctl(d, {"set", "axis.x.mode=switch_reapproach", "axis.x.latch_passes=3", "axis.x.max_latch_spread=1",
                   "sim.x.hysteresis=0.08", "sim.x.actual_position=5"});
  REQUIRE(r.code() == 0);
  REQUIRE(ctl(d, {"home", "x"}).code() == 0);
  r = ctl(d, {"health"});
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("hysteresis") != std::string::npos);
  CHECK(r.out.find("\nX ") != std::string::npos);
  auto j = json_of(ctl(d, {"--json", "health"}));
  CHECK(j["x"]["latch_passes"] == 3);
  CHECK(j["x"]["hysteresis"].get<double>() == Approx(0.08).margin(0.01));
  CHECK(j["x"]["latch_spread"].get<double>() < 0.05);
  CHECK(j["x"]["unit"] == "mm");
  CHECK(j["x"]["warnings"].empty());
  CHECK_FALSE(j.contains("a"));  // A does not home on a new module

  // An index pulse 0.02 pitch (0.1 mm) beyond the release edge (the cam's end + 0.08 mm).
  r = ctl(d, {"set", "axis.x.mode=switch_index", "axis.x.index_pitch=5", "sim.x.index_pitch=5",
              "sim.x.index_offset=0.18", "sim.x.noise=0"});
  REQUIRE(r.code() == 0);
  REQUIRE(ctl(d, {"home", "x"}).code() == 0);
  r = ctl(d, {"health"});
  SHOW(r);
  CHECK(r.out.find("index pulse 0.100 mm from the switch edge (index_pitch 5 mm)") != std::string::npos);
  CHECK(r.out.find("move the cam or the encoder's index by about half a pitch") != std::string::npos);
  j = json_of(ctl(d, {"--json", "health"}));
  CHECK(j["x"]["index_distance"].get<double>() == Approx(0.1).margin(0.005));
  CHECK(j["x"]["warnings"].size() == 1);
}

TEST_CASE("a limit switch trip names the end it was at, over Modbus and in homingctl status, and the inputs read active") {
  Daemon d;
  Client c = Client::tcp(d.port());
  REQUIRE(ctl(d, {"set", "sim.x.limit_min=-3", "sim.x.limit_max=990", "axis.x.limits_fitted=1",
                  "axis.x.limit_overtravel=2"}).code() == 0);
  REQUIRE(ctl(d, {"home", "x"}).code() == 0);
  CHECK(c.read("axis.x.limit_min") == 0);
  CHECK(c.read("axis.x.limit_max") == 0);
  auto r = ctl(d, {"move", "x", "-10"});
  SHOW(r);
  REQUIRE(c.read("axis.x.alarm") == static_cast<int>(homing::AlarmCode::limit_switch));
  CHECK(c.read("axis.x.alarm_rule") == 1);  // the negative end
  CHECK(c.read("axis.x.limit_min") == 1);   // the carriage stands on it
  CHECK(c.read("axis.x.limit_max") == 0);
  r = ctl(d, {"status"});
  SHOW(r);
  CHECK(r.out.find("negative limit switch tripped") != std::string::npos);
  CHECK(r.out.find("positive limit switch") == std::string::npos);
  CHECK(r.out.find(" -on ") != std::string::npos);
}
