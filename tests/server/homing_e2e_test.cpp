// The real homingd over Modbus/TCP (libmodbus): axes configured over the
// wire, a full home-all with the default sequence (Z, then X+Y) watched phase
// by phase and checked against the simulator unit's truth; commands refused
// in the wrong state; a jog that stops when its client goes; the watchdog;
// 50 clients polling while homing runs; settings that survive a restart; a
// clean SIGTERM during motion.
#include <catch2/catch.hpp>

#include <atomic>
#include <map>
#include <set>

#include "daemon.hpp"
#include "homing/phases.hpp"
#include "homing/status.hpp"

using namespace e2e;
using homing::Phase;

namespace {

constexpr const char* kAxes[] = {"x", "y", "z"};

std::string ax(const char* axis, const char* field) { return std::string("axis.") + axis + "." + field; }
std::string sim(const char* axis, const char* field) { return std::string("sim.") + axis + "." + field; }

int phase_of(Client& c, const char* axis) { return static_cast<int>(c.read(ax(axis, "phase"))); }
int state_of(Client& c) { return static_cast<int>(c.read("status.state")); }
int result_of(Client& c) { return static_cast<int>(c.read("status.last_command_result")); }

// The watchdog of the tests that let it expire: long enough that a Modbus
// round trip on a loaded machine does not outlast it while the host beats.
constexpr int kWatchdogMs = 500;

// The host's heartbeat, written every 20 ms until done() holds (10 s at most);
// alarm says whether status.alarm was seen meanwhile. Whether done() held.
bool beat_until(Client& c, std::uint16_t& beat, bool& alarm, const std::function<bool()>& done) {
  return wait_until(
      [&] {
        c.set("host.heartbeat", beat++);
        alarm = alarm || c.read("status.alarm") != 0;
        return done();
      },
      10s, 20ms);
}

// These registers watched while machine_s of machine time passes (10 s at
// most): "nothing moved" across the whole window. At rest the control loop
// idles, a period per slow tick that advances the machine by the whole
// stretch (docs/architecture.md), so the window is counted on the wall clock
// at the daemon's time scale (a machine at rest is never held back), and
// holds at least a few periods, so the loop is seen running through it.
SteadyWatch watch_still(Client& c, const std::vector<std::string>& names, double machine_s, double time_scale) {
  const auto from = c.read("diag.loop_periods");
  const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(machine_s / time_scale));
  return watch_steady(
      [&] {
        std::vector<std::int64_t> v;
        for (const auto& n : names) v.push_back(c.read(n));
        return v;
      },
      [&] { return Clock::now() >= until && c.read("diag.loop_periods") >= from + 3; }, 10s);
}

bool active(int phase) {
  return phase >= static_cast<int>(Phase::pre_move) && phase <= static_cast<int>(Phase::align_slave);
}

// Where the default simulated machine leaves a carriage homed with mode 2
// (release edge), direction negative: the sensor (active on [sensor_min,
// sensor_max]) releases `hysteresis` above sensor_max during the back-off,
// then the axis pulls off away from it.
double expected_actual_mm(Client& c, const char* axis) {
  const double sensor_max = c.read_mm(sim(axis, "sensor_max"));
  const double hysteresis = c.read_mm(sim(axis, "hysteresis"));
  const double pull_off = c.read_mm(ax(axis, "pull_off"));
  return sensor_max + hysteresis + pull_off;
}

struct Sample {
  int state = 0, step = 0;
  std::map<std::string, int> phase;
  int z_after = 0;  // Z's phase read again after X and Y (the reads are not one snapshot)
};

// Watches a home-all until the machine is homed or in alarm (bounded).
std::vector<Sample> watch_cycle(Client& c, std::chrono::milliseconds timeout) {
  std::vector<Sample> samples;
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline && samples.size() < 20000) {
    Sample s;
    s.state = state_of(c);
    s.step = static_cast<int>(c.read("status.sequence_step"));
    s.phase["z"] = phase_of(c, "z");
    s.phase["x"] = phase_of(c, "x");
    s.phase["y"] = phase_of(c, "y");
    s.z_after = phase_of(c, "z");
    samples.push_back(s);
    if (s.state == static_cast<int>(homing::MachineState::homed) ||
        s.state == static_cast<int>(homing::MachineState::alarm))
      break;
    std::this_thread::sleep_for(2ms);
  }
  return samples;
}

void check_homed_against_truth(Client& c, double tolerance_mm = 0.02) {
  for (const char* a : kAxes) {
    INFO("axis " << a);
    CHECK(c.read(ax(a, "homed")) == 1);
    CHECK(c.read(ax(a, "alarm")) == 0);
    CHECK(c.read(ax(a, "position")) == c.read(ax(a, "home_position")));
    CHECK(c.read_mm(sim(a, "actual_position")) == Approx(expected_actual_mm(c, a)).margin(tolerance_mm));
  }
}

}  // namespace

TEST_CASE("axes configured over Modbus home in the default sequence Z then X+Y, matching the simulator") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  REQUIRE(c.read("status.map_version") == registers::kMapVersion);
  REQUIRE(c.read("sequence.step1") == 0b100);  // Z
  REQUIRE(c.read("sequence.step2") == 0b011);  // X + Y

  // Configure: pull-offs, home positions, a faster Z seek (FC 16 each, 32-bit whole).
  c.set("axis.x.pull_off", um(2.0));
  c.set("axis.x.home_position", um(-5.0));
  c.set("axis.y.pull_off", um(1.5));
  c.set("axis.y.home_position", um(12.345));
  c.set("axis.z.seek_feedrate", 1500);
  c.set("axis.z.home_position", um(80.0));
  CHECK(c.read("axis.x.pull_off") == 2000);
  CHECK(c.read("axis.x.home_position") == -5000);
  CHECK(c.read("axis.y.home_position") == 12345);
  CHECK(c.read("axis.z.seek_feedrate") == 1500);
  for (const char* a : kAxes) CHECK(c.read(ax(a, "homed")) == 0);

  REQUIRE(c.write("cmd.home_all", 1) == 0);
  const auto samples = watch_cycle(c, 20s);
  REQUIRE_FALSE(samples.empty());
  REQUIRE(samples.back().state == static_cast<int>(homing::MachineState::homed));
  CHECK(result_of(c) == static_cast<int>(homing::CommandResult::accepted));

  // The sequence: Z moves alone in step 1 while X and Y wait; X and Y move
  // only once Z is done, in step 2.
  bool z_alone = false, xy_moved = false;
  std::set<int> z_phases, x_phases, steps;
  for (const Sample& s : samples) {
    steps.insert(s.step);
    z_phases.insert(s.phase.at("z"));
    x_phases.insert(s.phase.at("x"));
    if (active(s.phase.at("z")) && active(s.z_after)) {
      CHECK_FALSE(active(s.phase.at("x")));
      CHECK_FALSE(active(s.phase.at("y")));
      if (s.phase.at("x") == static_cast<int>(Phase::waiting) && s.phase.at("y") == static_cast<int>(Phase::waiting)) {
        z_alone = true;
        if (s.state == static_cast<int>(homing::MachineState::homing)) CHECK(s.step == 1);
      }
    }
    if (active(s.phase.at("x")) || active(s.phase.at("y"))) {
      xy_moved = true;
      CHECK(s.z_after == static_cast<int>(Phase::done));
    }
  }
  CHECK(z_alone);
  CHECK(xy_moved);
  CHECK(steps.count(1) == 1);
  CHECK(steps.count(2) == 1);
  CHECK(steps.count(3) == 0);
  for (Phase ph : {Phase::seek, Phase::back_off, Phase::done}) {
    const int p = static_cast<int>(ph);
    INFO("phase " << p);
    CHECK(z_phases.count(p) == 1);
    CHECK(x_phases.count(p) == 1);
  }

  // Positions: the assigned home position; the truth: release edge + pull-off.
  CHECK(c.read("status.homing_cycles") == 1);
  CHECK(c.read("status.homing") == 0);
  CHECK(c.read("status.sequence_step") == 0);
  check_homed_against_truth(c);
  CHECK(c.read("axis.y.position") == 12345);
  CHECK(c.read("axis.z.position") == 80000);
}

TEST_CASE("commands in the wrong state are refused with their code and move nothing") {
  Daemon d({.time_scale = 10});
  Client c = Client::tcp(d.port());
  const auto actual_x = c.read("sim.x.actual_position");
  const auto actual_z = c.read("sim.z.actual_position");

  // E-stop pressed: homing refused (refused_estop = 4).
  c.set("sim.estop", 1);
  REQUIRE(wait_until([&] { return c.read("status.estop") == 1; }, 2s));
  CHECK((c.read("status.interlocks") & homing::interlock::estop) != 0);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return result_of(c) == static_cast<int>(homing::CommandResult::refused_estop); }, 2s));
  // Nothing starts: watched over 2 s of machine time.
  const SteadyWatch refused_home =
      watch_still(c, {"status.homing", "sim.x.actual_position", "sim.z.actual_position"}, 2.0, 10);
  CHECK(refused_home.window_ended);
  CHECK(refused_home.steady);
  CHECK(refused_home.first == std::vector<std::int64_t>{0, actual_x, actual_z});

  // Released, the e-stop alarm stays latched: a jog is refused (refused_alarm = 3).
  c.set("sim.estop", 0);
  REQUIRE(wait_until([&] { return c.read("status.estop") == 0; }, 2s));
  CHECK(c.read("status.alarm") == 1);
  CHECK((c.read("status.interlocks") & homing::interlock::alarm_latched) != 0);
  REQUIRE(c.write("cmd.jog_plus.x", 1) == 0);
  REQUIRE(wait_until([&] { return result_of(c) == static_cast<int>(homing::CommandResult::refused_alarm); }, 2s));
  const SteadyWatch refused_jog = watch_still(c, {"axis.x.velocity", "sim.x.actual_position"}, 2.0, 10);
  CHECK(refused_jog.window_ended);
  CHECK(refused_jog.steady);
  CHECK(refused_jog.first == std::vector<std::int64_t>{0, actual_x});
  REQUIRE(c.write("cmd.jog_plus.x", 0) == 0);

  // Reset: the alarm clears, nothing blocks but homing itself.
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 0; }, 2s));
  CHECK(state_of(c) == static_cast<int>(homing::MachineState::not_homed));

  // Permit required and off: refused_no_permit = 8; with the permit, accepted.
  c.set("global.permit_required", 1);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return result_of(c) == static_cast<int>(homing::CommandResult::refused_no_permit); }, 2s));
  CHECK((c.read("status.interlocks") & homing::interlock::permit_missing) != 0);
  CHECK(c.read("status.homing") == 0);
  c.set("host.homing_permit", 1);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.homing") == 1; }, 2s));
  CHECK(result_of(c) == static_cast<int>(homing::CommandResult::accepted));
  // The same command again while it runs: not restarted (already_running = 2).
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  REQUIRE(wait_until([&] { return result_of(c) == static_cast<int>(homing::CommandResult::already_running); }, 2s));
  CHECK(c.read("status.homing") == 1);
  REQUIRE(wait_until([&] { return state_of(c) == static_cast<int>(homing::MachineState::homed); }, 20s));
  check_homed_against_truth(c);
}

TEST_CASE("a jog whose client disconnects stops") {
  Daemon d({.time_scale = 10});
  Client watcher = Client::tcp(d.port());
  {
    Client jogger = Client::tcp(d.port());
    REQUIRE(jogger.write("cmd.jog_plus.x", 1) == 0);
    REQUIRE(wait_until([&] { return watcher.read("axis.x.velocity") > 0; }, 2s));
    CHECK(jogger.read("cmd.jog_plus.x") == 1);  // reads back the held state
    CHECK(phase_of(watcher, "x") == static_cast<int>(Phase::jog));
    const auto p0 = watcher.read("axis.x.position");
    CHECK(wait_until([&] { return watcher.read("axis.x.position") > p0; }, 5s));
    jogger.close();  // the connection goes, without writing 0
  }
  REQUIRE(wait_until([&] { return watcher.read("axis.x.velocity") == 0 && watcher.read("axis.x.busy") == 0; }, 3s));
  // At rest for good: watched over 3 s of machine time.
  const SteadyWatch still = watch_still(watcher, {"axis.x.position", "sim.x.actual_position"}, 3.0, 10);
  INFO("samples " << still.samples);
  CHECK(still.window_ended);
  CHECK(still.steady);
  CHECK(watcher.read("axis.x.busy") == 0);
  CHECK(watcher.read("status.alarm") == 0);
}

TEST_CASE("an expired watchdog stops a homing cycle with communication lost on the moving axis") {
  Daemon d({.time_scale = 2});
  Client c = Client::tcp(d.port());
  c.set("global.watchdog_ms", kWatchdogMs);
  std::uint16_t beat = 1;
  c.set("host.heartbeat", beat++);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  // The host beats while Z seeks (6 s of machine time, 3000 control periods
  // here) for twice the watchdog's time: the cycle goes on, no alarm.
  const auto periods = c.read("diag.loop_periods");
  bool alarm = false;
  REQUIRE(beat_until(c, beat, alarm, [&] { return c.read("diag.loop_periods") > periods + 2 * kWatchdogMs; }));
  CHECK_FALSE(alarm);
  REQUIRE(c.read("status.homing") == 1);
  REQUIRE(phase_of(c, "z") == static_cast<int>(Phase::seek));
  // Now the host goes silent after one last beat. The alarm never comes
  // before watchdog_ms after that beat was sent (it can only come later).
  const auto last_beat = Clock::now();
  c.set("host.heartbeat", beat++);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 1; }, 10s));
  CHECK(Clock::now() - last_beat >= std::chrono::milliseconds(kWatchdogMs));
  CHECK(c.read("axis.z.alarm") == static_cast<int>(homing::AlarmCode::communication_lost));
  CHECK(c.read("axis.z.alarm_phase") == static_cast<int>(Phase::seek));
  CHECK(c.read("status.homing") == 0);
  REQUIRE(wait_until([&] { return c.read("axis.z.velocity") == 0; }, 5s));
  // Stopped for good: watched over 1 s of machine time.
  const SteadyWatch still = watch_still(c, {"sim.z.actual_position", "axis.z.position"}, 1.0, 2);
  INFO("samples " << still.samples);
  CHECK(still.window_ended);
  CHECK(still.steady);
  CHECK(c.read("axis.z.homed") == 0);

  // With the heartbeat kept alive, the same cycle completes. The host's beat
  // comes every 40 ms or so; on a loaded shared machine a Modbus round trip
  // can stall far longer, so this half gives the watchdog a margin.
  // While the heartbeat stays stale the interlock shows it, and a reset is
  // refused: its cause is still present.
  CHECK((c.read("status.interlocks") & homing::interlock::communication_lost) != 0);
  const auto judged = c.read("status.command_count");
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") > judged; }, 2s));
  CHECK(c.read("status.last_command_result") == static_cast<int>(homing::CommandResult::refused_cause_present));
  CHECK(c.read("status.alarm") == 1);
  c.set("global.watchdog_ms", 1000);
  c.set("host.heartbeat", beat++);
  REQUIRE(c.write("cmd.reset_alarm", 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 0; }, 2s));
  c.set("host.heartbeat", beat++);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  const bool homed = wait_until(
      [&] {
        c.set("host.heartbeat", beat++);
        return state_of(c) == static_cast<int>(homing::MachineState::homed) || c.read("status.alarm") == 1;
      },
      30s, 40ms);
  REQUIRE(homed);
  CHECK(state_of(c) == static_cast<int>(homing::MachineState::homed));
  check_homed_against_truth(c);
}

TEST_CASE("50 clients poll without error while a home-all runs") {
  Daemon d({.time_scale = 10, .extra = {"--max-clients", "64"}});
  Client c = Client::tcp(d.port());
  constexpr int kClients = 50;
  constexpr int kMaxPolls = 1500;
  std::atomic<bool> done{false};
  std::atomic<int> errors{0}, connected{0};
  std::vector<int> polls(kClients, 0);
  std::vector<std::string> first_error(kClients);
  std::vector<std::thread> threads;
  const auto deadline = Clock::now() + 30s;
  for (int i = 0; i < kClients; ++i) {
    threads.emplace_back([&, i] {
      try {
        Client p = Client::tcp(d.port());
        ++connected;
        while (!done && polls[i] < kMaxPolls && Clock::now() < deadline) {
          auto status = p.holding(0, 6);  // sequence
          std::uint16_t words[20];
          const int rc1 = modbus_read_input_registers(p.ctx(), 0, 10, words);
          const int rc2 = modbus_read_input_registers(p.ctx(), 100 + 100 * (i % 3), 20, words);
          if (!status || rc1 != 10 || rc2 != 20) {
            if (errors++ == 0 || first_error[i].empty()) first_error[i] = modbus_strerror(errno);
          }
          ++polls[i];
          std::this_thread::sleep_for(5ms);
        }
      } catch (const std::exception& e) {
        ++errors;
        first_error[i] = e.what();
      }
    });
  }
  REQUIRE(wait_until([&] { return connected.load() == kClients || errors.load() > 0; }, 10s));
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  const bool finished = wait_until(
      [&] {
        const int s = state_of(c);
        return s == static_cast<int>(homing::MachineState::homed) || s == static_cast<int>(homing::MachineState::alarm);
      },
      25s, 20ms);
  done = true;
  for (auto& t : threads) t.join();
  std::string why;
  for (const auto& e : first_error)
    if (!e.empty()) why = e;
  INFO("first error: " << why);
  CHECK(errors.load() == 0);
  CHECK(connected.load() == kClients);
  for (int i = 0; i < kClients; ++i) CHECK(polls[i] >= 5);
  REQUIRE(finished);
  CHECK(state_of(c) == static_cast<int>(homing::MachineState::homed));
  check_homed_against_truth(c);
}

TEST_CASE("settings written over Modbus survive a restart of homingd on the same database") {
  TempDir dir;
  const std::string db = dir.file("persist.db");
  const std::vector<std::pair<std::string, std::int64_t>> written{
      {"axis.x.pull_off", 3210},      {"axis.y.home_position", -42000}, {"axis.z.seek_feedrate", 1800},
      {"axis.x.direction", 1},        {"sequence.step1", 0b001},        {"sequence.step2", 0b110},
      {"global.watchdog_ms", 750},    {"axis.c.max_seek_travel", 123456},
  };
  {
    Daemon d({.db = db, .time_scale = 10});
    Client c = Client::tcp(d.port());
    for (const auto& [name, raw] : written) c.set(name, raw);
    c.set("host.heartbeat", 99);        // not persisted
    c.set("axis.x.target", um(12.5));   // not persisted
    for (const auto& [name, raw] : written) CHECK(c.read(name) == raw);
    c.close();
    const auto st = d.stop(SIGTERM);
    REQUIRE(st);
    CHECK(WIFEXITED(*st));
    CHECK(WEXITSTATUS(*st) == 0);
  }
  Daemon again({.db = db, .time_scale = 10});
  Client c = Client::tcp(again.port());
  for (const auto& [name, raw] : written) {
    INFO(name);
    CHECK(c.read(name) == raw);
  }
  CHECK(c.read("host.heartbeat") == 0);
  CHECK(c.read("axis.x.target") == 0);
  CHECK(c.read("axis.x.pull_off") == 3210);
}

TEST_CASE("SIGTERM during motion stops the motion and exits 0, SIGINT at rest exits 0") {
  SECTION("SIGTERM while homing") {
    Daemon d({.time_scale = 5});
    Client c = Client::tcp(d.port());
    REQUIRE(c.write("cmd.home_all", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("axis.z.velocity") != 0; }, 2s));
    c.close();
    const auto t0 = Clock::now();
    const auto st = d.stop(SIGTERM, 10s);
    REQUIRE(st);
    CHECK(Clock::now() - t0 < 5s);
    CHECK(WIFEXITED(*st));
    CHECK(WEXITSTATUS(*st) == 0);
    const std::string log = d.log();
    INFO(log);
    CHECK(log.find("stopping motion") != std::string::npos);
    CHECK(log.find("stopped cleanly") != std::string::npos);
  }
  SECTION("SIGTERM while jogging") {
    Daemon d({.time_scale = 5});
    Client c = Client::tcp(d.port());
    REQUIRE(c.write("cmd.jog_minus.y", 1) == 0);
    REQUIRE(wait_until([&] { return c.read("axis.y.velocity") < 0; }, 2s));
    const auto st = d.stop(SIGTERM, 10s);
    REQUIRE(st);
    CHECK(WIFEXITED(*st));
    CHECK(WEXITSTATUS(*st) == 0);
    CHECK(d.log().find("stopped cleanly") != std::string::npos);
  }
  SECTION("SIGINT at rest") {
    Daemon d({.time_scale = 5});
    const auto st = d.stop(SIGINT, 10s);
    REQUIRE(st);
    CHECK(WIFEXITED(*st));
    CHECK(WEXITSTATUS(*st) == 0);
  }
}

// The alarm names the phase the moving axis was in; axes waiting for a later
// sequence step were not moving and get no alarm of their own.
TEST_CASE("communication lost records the phase the moving axis was in") {
  Daemon d({.time_scale = 2});
  Client c = Client::tcp(d.port());
  c.set("global.watchdog_ms", kWatchdogMs);
  std::uint16_t beat = 1;
  c.set("host.heartbeat", beat++);
  REQUIRE(c.write("cmd.home_all", 1) == 0);
  bool alarm = false;
  REQUIRE(beat_until(c, beat, alarm, [&] { return phase_of(c, "z") == static_cast<int>(Phase::seek); }));
  REQUIRE_FALSE(alarm);
  REQUIRE(wait_until([&] { return c.read("status.alarm") == 1; }, 10s));
  CHECK(c.read("axis.z.alarm") == static_cast<int>(homing::AlarmCode::communication_lost));
  CHECK(c.read("axis.z.alarm_phase") == static_cast<int>(Phase::seek));
  CHECK(c.read("axis.x.alarm") == 0);
}
