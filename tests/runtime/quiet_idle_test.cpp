// The quiet idle (server/control_loop.hpp): when nothing moves and nothing
// is pending the control thread waits for a wake, an input event, the
// watchdog's deadline or the slow tick instead of running a period every
// millisecond, and whatever comes is handled in the period that follows.
// The thread's turns are driven by hand on a fake waiter's clock: the tests
// assert on the sequence of waits and periods, never on wall time.
#include <catch2/catch.hpp>

#include <poll.h>

#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <thread>
#include <vector>

#include "homing/machine_io.hpp"
#include "homing/sim/simulator_io.hpp"
#include "registers/defaults.hpp"
#include "registers/sim_bindings.hpp"
#include "server/control_loop.hpp"
#include "tests/gpiod/backend_fixture.hpp"

namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kPeriodNs = 1 * kMs;
constexpr std::int64_t kTickNs = server::ControlLoop::kQuietTickMs * kMs;

// A clock of its own: sleeps jump to their deadline, a wait ends early at the
// time the test scripted for a wake or for an input event.
struct FakeWaiter final : server::LoopWaiter {
  struct Wait {
    bool quiet = false;       // wait_until (quiet) or sleep_until (full rate, or the period's minimum spacing)
    std::int64_t from_ns = 0;
    std::int64_t deadline_ns = 0;
    std::int64_t ended_ns = 0;
    std::vector<int> fds;
  };
  std::int64_t now = 1'000 * kMs;
  std::vector<Wait> waits;
  bool woken = false;
  std::int64_t wake_after_ns = 0;             // a wake ends the wait this long after it began
  std::optional<std::int64_t> input_at_ns;    // an input event at this time (when fds are given)
  bool poll_fds = false;                      // the fds are real: an event is one of them readable

  std::int64_t now_ns() override { return now; }
  void sleep_until(std::int64_t deadline_ns) override {
    waits.push_back({false, now, deadline_ns, std::max(now, deadline_ns), {}});
    now = std::max(now, deadline_ns);
  }
  bool wait_until(std::int64_t deadline_ns, std::span<const int> fds) override {
    Wait w{true, now, deadline_ns, deadline_ns, {fds.begin(), fds.end()}};
    bool early = false;
    if (woken) {
      woken = false;
      w.ended_ns = now + wake_after_ns;
      early = true;
    } else if (input_at_ns && !fds.empty() && *input_at_ns < deadline_ns && (!poll_fds || readable(fds))) {
      w.ended_ns = std::max(now, *input_at_ns);
      input_at_ns.reset();
      early = true;
    }
    now = std::max(now, w.ended_ns);
    waits.push_back(w);
    return early;
  }
  void wake() override { woken = true; }

  static bool readable(std::span<const int> fds) {
    std::vector<pollfd> p;
    for (const int fd : fds) p.push_back(pollfd{fd, POLLIN, 0});
    return ::poll(p.data(), p.size(), 0) > 0;
  }
  const Wait& last() const { return waits.back(); }
};

struct Loop {
  FakeWaiter* waiter;
  std::unique_ptr<server::ControlLoop> loop;

  explicit Loop(std::unique_ptr<homing::MachineIo> io, homing::Settings settings = registers::default_settings(),
                double time_scale = 1.0) {
    auto w = std::make_unique<FakeWaiter>();
    waiter = w.get();
    loop = std::make_unique<server::ControlLoop>(settings, std::move(io), 1000, time_scale,
                                                 [p = w.get()] { return p->now; }, std::move(w));
  }
  static Loop simulated(homing::Settings settings = registers::default_settings(), double time_scale = 1.0) {
    return Loop(std::make_unique<homing::sim::SimulatorIo>(registers::default_sim_config()), settings, time_scale);
  }
  server::Snapshot snap() const { return loop->snapshot(); }
  void turn() { REQUIRE(loop->run_turn()); }
};

// A machine that changes only when the test says so, with an input event
// descriptor (never read: the fake waiter is told when it fires).
struct EventMachine final : homing::MachineIo {
  bool estop = false;
  int fd = 42;
  void advance(const homing::Outputs&, double) override {}
  homing::Inputs read() override {
    homing::Inputs in{};
    in.estop = estop;
    return in;
  }
  double quiet_for_s(const homing::Outputs&) const override { return std::numeric_limits<double>::infinity(); }
  std::span<const int> event_fds() const override { return {&fd, 1}; }
};

}  // namespace

TEST_CASE("an idle loop runs a period at the slow tick only, each advancing the machine by the whole stretch") {
  Loop l = Loop::simulated();
  REQUIRE(l.loop->quiet());
  const double t0_s = l.snap().machine_time_s;
  const std::uint64_t periods0 = l.snap().periods;
  const std::uint64_t steps0 = l.loop->stats().engine_steps;
  for (int i = 0; i < 5; ++i) l.turn();
  REQUIRE(l.waiter->waits.size() == 5);
  for (const FakeWaiter::Wait& w : l.waiter->waits) {
    CHECK(w.quiet);
    CHECK(w.deadline_ns - w.from_ns == kTickNs);
  }
  CHECK(l.snap().periods == periods0 + 5);
  CHECK(l.snap().machine_time_s - t0_s == Approx(5 * kTickNs * 1e-9));
  CHECK(l.snap().status.axes[0].position_mm == 0);  // at rest where it started
  CHECK(l.loop->stats().quiet_periods == 5);
  // Two engine steps a quiet period, not fifty: the stretch, then the period proper.
  CHECK(l.loop->stats().engine_steps - steps0 == 10);
}

TEST_CASE("a watcher of an idle loop sleeps through its slow ticks and wakes for a command or an alarm") {
  Loop l = Loop::simulated();
  l.turn();
  REQUIRE(l.snap().quiet);
  const std::uint64_t news = l.snap().news;
  CHECK_FALSE(l.loop->wait_for_news(news, std::chrono::milliseconds(1)));  // stepped by hand: nothing comes
  for (int i = 0; i < 3; ++i) l.turn();
  REQUIRE(l.waiter->last().ended_ns == l.waiter->last().deadline_ns);  // slow ticks, nothing woke them
  CHECK(l.snap().news == news);
  CHECK_FALSE(l.loop->wait_for_news(news, std::chrono::milliseconds(0)));
  // A command wakes the loop: its period is news, even one the command leaves quiet.
  l.loop->submit(homing::Commands{.reset_alarm = true}, true);
  l.turn();
  REQUIRE(l.snap().quiet);
  CHECK(l.loop->wait_for_news(news, std::chrono::milliseconds(0)));
  const std::uint64_t after_reset = l.snap().news;
  l.turn();
  CHECK(l.snap().news == after_reset);
  l.loop->submit(homing::Commands{.home_all = true}, true);
  l.turn();
  REQUIRE_FALSE(l.snap().quiet);  // homing: the full rate, the watcher does not wait
  CHECK(l.loop->wait_for_news(l.snap().news, std::chrono::milliseconds(0)));
}

TEST_CASE("an alarm raised at a slow tick is news to a watcher of the idle loop") {
  auto machine = std::make_unique<EventMachine>();
  EventMachine* m = machine.get();
  Loop l(std::move(machine));
  for (int i = 0; i < 3; ++i) l.turn();
  REQUIRE(l.snap().quiet);
  const std::uint64_t news = l.snap().news;
  l.turn();
  REQUIRE(l.snap().news == news);
  m->estop = true;  // seen at the slow tick: this machine gives no event for it
  l.turn();
  REQUIRE(l.waiter->last().ended_ns == l.waiter->last().deadline_ns);
  REQUIRE(l.snap().status.global_alarm == homing::AlarmCode::emergency_stop);
  CHECK(l.loop->wait_for_news(news, std::chrono::milliseconds(0)));
}

TEST_CASE("a time-scaled simulator idles too, and its machine time keeps pace with the scale") {
  Loop l = Loop::simulated(registers::default_settings(), 20);
  const double t0_s = l.snap().machine_time_s;
  const std::uint64_t steps0 = l.loop->stats().engine_steps;
  for (int i = 0; i < 3; ++i) l.turn();
  CHECK(l.waiter->last().quiet);
  CHECK(l.snap().machine_time_s - t0_s == Approx(3 * kTickNs * 1e-9 * 20));
  CHECK(l.loop->stats().sim_held_back_periods == 0);  // a quiet stretch is not a late period
  // The stretch in one step, then the period proper in the scale's 20: not
  // the thousand of a second of simulated time at the full rate.
  CHECK(l.loop->stats().engine_steps - steps0 == 3 * 21);
}

TEST_CASE("after an idle stretch a start command wakes the loop and starts the cycle in that period, then the "
          "loop runs at the full rate") {
  Loop l = Loop::simulated();
  for (int i = 0; i < 3; ++i) l.turn();
  homing::Commands home{};
  home.home_all = true;
  l.waiter->wake_after_ns = 17 * kMs;  // the command comes 17 ms into the next quiet wait
  l.loop->submit(home, true);
  const double before_s = l.snap().machine_time_s;
  l.turn();
  const FakeWaiter::Wait woken = l.waiter->last();  // a copy: the next turn grows the vector
  CHECK(woken.quiet);
  CHECK(woken.ended_ns - woken.from_ns == 17 * kMs);
  CHECK(l.snap().status.homing);
  CHECK(l.snap().machine_time_s - before_s == Approx(0.017));
  CHECK_FALSE(l.loop->quiet());
  l.turn();
  CHECK_FALSE(l.waiter->last().quiet);
  CHECK(l.waiter->last().deadline_ns - woken.ended_ns == kPeriodNs);
}

TEST_CASE("a wake right after a period still leaves a whole period before the next one") {
  Loop l = Loop::simulated();
  l.turn();
  l.waiter->wake_after_ns = 0;
  l.loop->submit(homing::Commands{.reset_alarm = true}, true);
  const std::int64_t last_period_ns = l.waiter->now;
  l.turn();
  // The wait ended at once; the loop then slept to one period after the last.
  REQUIRE(l.waiter->waits.size() >= 2);
  const FakeWaiter::Wait spacing = l.waiter->last();
  CHECK_FALSE(spacing.quiet);
  CHECK(spacing.deadline_ns == last_period_ns + kPeriodNs);
  CHECK(l.loop->quiet());  // a reset with nothing to reset leaves it idle
}

TEST_CASE("a simulator write to a quiet loop is answered in the period the wake begins") {
  // Stepped by hand the write runs at once (no thread); the wake is what a
  // running loop needs, and every mailbox entry point gives one.
  Loop l = Loop::simulated();
  l.turn();
  l.loop->set_permit_coil(true);
  CHECK(l.waiter->woken);
  l.turn();
  CHECK(l.waiter->last().deadline_ns - l.waiter->last().from_ns == kPeriodNs);  // the spacing after an early wake
  l.waiter->woken = false;
  l.loop->set_jog(0, 0, 1);
  CHECK(l.waiter->woken);
  l.waiter->woken = false;
  l.loop->set_settings(registers::default_settings());
  CHECK(l.waiter->woken);
  l.waiter->woken = false;
  l.loop->raise_settings_lost();
  CHECK(l.waiter->woken);
  l.waiter->woken = false;
  l.loop->restore_last_stops(homing::LastStops{});
  CHECK(l.waiter->woken);
  l.waiter->woken = false;
  l.loop->release_jogs(1);
  CHECK(l.waiter->woken);
  l.waiter->woken = false;
  l.loop->request_stop();
  CHECK(l.waiter->woken);
}

TEST_CASE("an input event wakes a quiet loop and the period at the event reads it") {
  auto machine = std::make_unique<EventMachine>();
  EventMachine* m = machine.get();
  Loop l(std::move(machine));
  l.turn();
  REQUIRE(l.waiter->last().quiet);
  CHECK(l.waiter->last().fds == std::vector<int>{42});  // the machine's event descriptors are waited on
  CHECK_FALSE(l.snap().status.estop);
  m->estop = true;
  l.waiter->input_at_ns = l.waiter->now + 23 * kMs;
  l.turn();
  CHECK(l.waiter->last().ended_ns - l.waiter->last().from_ns == 23 * kMs);
  CHECK(l.snap().status.estop);
  CHECK((l.snap().status.interlocks & homing::interlock::estop) != 0);
}

TEST_CASE("a GPIO line event wakes a quiet loop, the period drains it, and the next wait is a quiet one again") {
  auto chip = fixture::chip();
  fake::Chip* c = chip.get();
  auto waiter = std::make_unique<FakeWaiter>();
  FakeWaiter* w = waiter.get();
  std::int64_t* clock = &w->now;
  homing::gpiod::RunOptions run;
  run.start_pulse_thread = false;
  run.clocks.monotonic_ns = [clock] { return *clock; };
  run.clocks.realtime_ns = [clock] { return *clock + 1'700'000'000'000'000'000; };
  auto io = homing::gpiod::GpiodIo::open(fixture::config(), std::move(chip), run);
  REQUIRE(io);
  homing::Settings settings = registers::default_settings();
  server::ControlLoop loop(settings, std::move(*io), 1000, 1.0, [w] { return w->now; }, std::move(waiter));
  w->poll_fds = true;
  REQUIRE(loop.run_turn());
  REQUIRE(w->last().quiet);
  CHECK_FALSE(w->last().fds.empty());
  CHECK_FALSE(loop.snapshot().status.estop);
  // The e-stop is pressed 12 ms into the next wait.
  w->input_at_ns = w->now + 12 * kMs;
  c->play("estop", w->now + 12 * kMs, true);
  REQUIRE(loop.run_turn());
  CHECK(w->last().ended_ns - w->last().from_ns == 12 * kMs);
  CHECK(loop.snapshot().status.estop);
  // Drained by the period's read: nothing left readable, the loop idles again.
  CHECK_FALSE(FakeWaiter::readable(w->last().fds));
  REQUIRE(loop.run_turn());
  REQUIRE(loop.run_turn());
  CHECK(w->last().quiet);
  CHECK(w->last().deadline_ns - w->last().from_ns == kTickNs);
}

TEST_CASE("the watchdog ends a quiet wait at its deadline, and communication_lost shows in that period") {
  homing::Settings settings = registers::default_settings();
  settings.global.watchdog_ms = 120;
  Loop l = Loop::simulated(settings);
  const std::int64_t t0 = l.waiter->now;  // the heartbeat's last change: the start
  // The e-stop pressed, a jog held over Modbus is refused: nothing moves, yet
  // the watchdog watches that client.
  REQUIRE(l.loop->edit_sim([](homing::sim::SimulatorControls& sim, const homing::Outputs&) { sim.set_estop(true); },
                           std::chrono::seconds(1)));
  l.loop->set_jog(0, 1, 7);
  l.turn();  // woken at once: the period one period after the last takes the jog
  REQUIRE(l.loop->quiet());
  REQUIRE(l.snap().status.last_command_result == homing::CommandResult::refused_estop);
  l.turn();
  l.turn();
  CHECK(l.waiter->last().deadline_ns - l.waiter->last().from_ns == kTickNs);
  CHECK((l.snap().status.interlocks & homing::interlock::communication_lost) == 0);
  l.turn();
  CHECK(l.waiter->last().quiet);
  CHECK(l.waiter->last().deadline_ns == t0 + 120 * kMs + 1);
  CHECK((l.snap().status.interlocks & homing::interlock::communication_lost) != 0);
  // Shown: the loop idles at its slow tick again, not at the full rate.
  l.turn();
  CHECK(l.waiter->last().quiet);
  CHECK(l.waiter->last().deadline_ns - l.waiter->last().from_ns == kTickNs);
}

TEST_CASE("with nothing moving a stale heartbeat shows communication_lost at the watchdog's deadline, refuses a reset, "
          "and clears once the heartbeat changes, without a reset") {
  homing::Settings settings = registers::default_settings();
  settings.global.watchdog_ms = 120;
  Loop l = Loop::simulated(settings);
  const std::int64_t t0 = l.waiter->now;  // the heartbeat's last change: the start
  l.turn();
  CHECK((l.snap().status.interlocks & homing::interlock::communication_lost) == 0);
  // Quiet, yet the loop wakes at the watchdog's deadline to show it.
  for (int i = 0; i < 5 && l.waiter->now <= t0 + 120 * kMs; ++i) l.turn();
  l.turn();
  CHECK((l.snap().status.interlocks & homing::interlock::communication_lost) != 0);
  CHECK(l.snap().status.axes[0].alarm.code == homing::AlarmCode::none);  // nothing moved: no alarm
  homing::Commands reset;
  reset.reset_alarm = true;
  l.loop->submit(reset, true);
  l.turn();
  CHECK(l.snap().status.last_command_result == homing::CommandResult::refused_cause_present);
  l.turn();  // the loop idles again: only a wake ends its wait early
  REQUIRE_FALSE(l.waiter->woken);
  l.loop->heartbeat_written(1);
  // The heartbeat back wakes the loop: the interlock clears in the next
  // period, not at the slow tick (a PLC's cmd.home_axes a scan later).
  CHECK(l.waiter->woken);
  l.turn();
  CHECK(l.waiter->last().ended_ns - l.waiter->last().from_ns <= kMs);  // a period, not the slow tick
  CHECK((l.snap().status.interlocks & homing::interlock::communication_lost) == 0);
  // The same value again is no heartbeat, and a fresh one wakes nothing.
  l.loop->heartbeat_written(2);
  l.turn();
  l.loop->heartbeat_written(3);
  CHECK_FALSE(l.waiter->woken);
}

TEST_CASE("a simulator write to a running quiet loop wakes it: the write is not left for the slow tick") {
  // The real thread and waiter. Whether the write was taken by a woken
  // period or at a tick is counted by the loop itself (woken_periods), so
  // nothing here depends on how fast the machine is.
  server::ControlLoop loop(registers::default_settings(),
                           std::make_unique<homing::sim::SimulatorIo>(registers::default_sim_config()), 1000, 1.0);
  loop.start();
  auto wait_for = [&](auto pred) {
    for (int i = 0; i < 1000 && !pred(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    return pred();
  };
  REQUIRE(wait_for([&] { return loop.stats().quiet_periods >= 2; }));
  const std::uint64_t woken = loop.stats().woken_periods;
  for (int i = 0; i < 3; ++i) {
    const bool shown = loop.edit_sim(
        [](homing::sim::SimulatorControls& sim, const homing::Outputs&) { sim.set_start_button(false); },
        std::chrono::seconds(5));
    REQUIRE(shown);
  }
  CHECK(wait_for([&] { return loop.stats().woken_periods >= woken + 3; }));
  loop.stop();
}

TEST_CASE("a simulator's next scheduled change ends a quiet wait at its time") {
  homing::Settings settings = registers::default_settings();
  settings.axes[0].debounce_ms = 2;  // settles long before the contact stops bouncing
  Loop l = Loop::simulated(settings);
  l.turn();
  // The carriage placed onto its switch, whose contact bounces for up to 30 ms.
  REQUIRE(l.loop->edit_sim(
      [](homing::sim::SimulatorControls& sim, const homing::Outputs&) {
        homing::sim::AxisConfig c = sim.view().config.axes[0];
        c.bounce_ms = 30;
        sim.set_axis_config(0, c);
        sim.place(0, (c.sensor_min_mm + c.sensor_max_mm) / 2);
      },
      std::chrono::seconds(1)));
  l.waiter->wake();  // as a running loop's edit does (stepped by hand, the edit ran at once)
  l.turn();          // the edge and its bounce begin in this period
  l.waiter->waits.clear();
  for (int i = 0; i < 100 && (l.waiter->waits.empty() || !l.waiter->last().quiet ||
                              l.waiter->last().deadline_ns - l.waiter->last().from_ns == kTickNs);
       ++i)
    l.turn();
  // A quiet wait shorter than the slow tick: it ended at the next bounce toggle.
  REQUIRE(l.waiter->last().quiet);
  CHECK(l.waiter->last().deadline_ns - l.waiter->last().from_ns < kTickNs);
  CHECK(l.waiter->last().ended_ns == l.waiter->last().deadline_ns);
  for (int i = 0; i < 20; ++i) l.turn();  // the bounce over: the slow tick again
  CHECK(l.waiter->last().deadline_ns - l.waiter->last().from_ns == kTickNs);
  CHECK(l.snap().status.axes[0].sensor);
}
