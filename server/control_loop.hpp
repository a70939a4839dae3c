#pragma once
// The runtime: owns time and the control thread. Every period (absolute
// deadlines on CLOCK_MONOTONIC) it advances the machine, steps the engine and
// publishes a snapshot. The Modbus side talks to it only through mailboxes
// that the loop takes with try_lock, so a busy server never delays a period.
// While quiet (nothing moves, nothing pending, nothing scheduled) it runs a
// period only on a wake (any mailbox news), an input event, the machine's
// next scheduled change, the watchdog's deadline or the slow tick
// (kQuietTickMs), and returns to the full rate in the period that follows.
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>

#include "status_events.hpp"
#include <string_view>
#include <thread>
#include <vector>

#include "homing/engine.hpp"
#include "homing/last_stop.hpp"
#include "homing/machine_io.hpp"
#include "homing/sim/simulator_controls.hpp"
#include "loop_waiter.hpp"
#include "trace.hpp"

namespace server {

// Everything a Modbus read may need, copied whole under one lock: a 32-bit
// position is never half old, half new.
struct Snapshot {
  homing::Status status{};
  homing::Outputs outputs{};
  bool has_sim = false;             // the machine is the simulator: sim is what it shows
  homing::sim::SimulatorView sim{};
  std::uint64_t sim_edits_applied = 0;  // sequence number of the last simulator edit shown here
  double machine_time_s = 0;
  std::uint64_t periods = 0;
  // The period ended quiet: the loop idles (a period at its slow tick) until
  // something comes (ControlLoop::kQuietTickMs).
  bool quiet = false;
  // Counts the published periods that brought what a watcher acts on: every
  // period at the full rate, the first quiet one, one that raised a status
  // event (an alarm) or judged a command. A slow tick, a simulator edit or an
  // input edge that changes nothing else is no news: a watcher of the idle
  // loop (wait_for_news) sleeps through it.
  std::uint64_t news = 0;
  StatusEvents events;  // what changed period by period, for readers that sample
};

// Loop timing figures (benchmarks read them).
struct LoopStats {
  static constexpr std::size_t kBuckets = 4096;  // lateness histogram, 1 µs per bucket, last = beyond
  std::array<std::uint64_t, kBuckets> lateness_us_histogram{};
  std::uint64_t periods = 0;
  std::uint64_t late_periods = 0;  // started more than one period after their deadline
  // Periods in which the simulated machine was held back (ControlLoop::kSimCatchUpMaxS):
  // the computer could not keep up with --time-scale, so the simulation ran slower.
  std::uint64_t sim_held_back_periods = 0;
  // Periods that ended a quiet wait (the loop ran none in the stretch
  // before them), and of those the ones a wake or an input event began.
  std::uint64_t quiet_periods = 0;
  std::uint64_t woken_periods = 0;
  double max_lateness_us = 0;
  double engine_us_total = 0;
  std::uint64_t engine_steps = 0;
  // Lateness (µs) below which a fraction q of the periods started.
  double lateness_percentile_us(double q) const;
};

// How the motion that ran when stop() was called came to rest: the log's
// account of a SIGTERM (README: "stops all motion (controlled deceleration)").
struct StopReport {
  struct Axis {
    bool moving = false;        // it moved when the stop began
    double velocity_mm_per_s = 0;  // then
    double from_mm = 0;         // machine coordinates, then
    double rest_mm = 0;         // where it came to rest
    std::string_view unit = "mm";  // of the kind the axis moves with (homing::axis_unit)
  };
  std::array<Axis, homing::kAxisCount> axes{};
  double machine_s = 0;  // machine time the stop took
  bool at_rest = true;   // false: still moving when the 10 s bound ended the wait
  // What homingd keeps of each axis for the next start (homing/trust.hpp):
  // clean only for an axis homed, at rest, with no alarm latched, once the
  // whole stop came to rest.
  homing::LastStops last_stops{};
  // The simulator's carriages where they came to rest (simulator backend only).
  std::optional<std::array<double, homing::kAxisCount>> sim_carriages_mm;
};

// Nanoseconds since an arbitrary point (CLOCK_MONOTONIC).
std::int64_t monotonic_ns();

class ControlLoop {
 public:
  // An edit of the live simulator through its backend's controls, run inside
  // the loop before the machine advances; next = the outputs that period is
  // about to run (to tell which carriages move: SimulatorControls::in_motion).
  using SimEdit = std::function<void(homing::sim::SimulatorControls& sim, const homing::Outputs& next)>;

  // Nanoseconds on a monotonic clock: what the communication watchdog
  // (global.watchdog_ms) measures heartbeats against.
  using Clock = std::function<std::int64_t()>;

  // watchdog_clock: the wall clock (monotonic_ns) in homingd; a test may give
  // one that follows its simulated periods, so the watchdog is deterministic.
  // waiter: how the thread waits (nullptr: make_poll_waiter()); a test gives
  // a fake on its own clock and drives run_turn() by hand.
  ControlLoop(const homing::Settings& settings, std::unique_ptr<homing::MachineIo> io, int period_us,
              double time_scale, Clock watchdog_clock = monotonic_ns, std::unique_ptr<LoopWaiter> waiter = nullptr);
  ~ControlLoop();
  ControlLoop(const ControlLoop&) = delete;
  ControlLoop& operator=(const ControlLoop&) = delete;

  // rt_priority > 0: SCHED_FIFO at that priority for the control thread
  // (a warning and normal scheduling when the system refuses).
  void start(int rt_priority = 0);
  // Begins the stop without waiting: motion decelerates (abort) and no new
  // motion command is taken from now on.
  void request_stop() {
    stop_requested_ = true;
    waiter_->wake();
  }
  // Stops motion (abort, decelerate) and joins the thread.
  void stop();
  // After stop(): how the axes that moved came to rest.
  const StopReport& stop_report() const { return stop_report_; }

  // One-shot commands; merged until the loop takes them.
  void submit(const homing::Commands& commands, bool from_modbus);
  // The jog of an axis now (+1, -1, 0 = stop), for an owner (a client
  // connection); which client may start or stop it is the service's to
  // judge (server/jog_buttons.hpp).
  void set_jog(std::size_t axis, std::int8_t direction, std::uint64_t owner);
  // Releases every jog held by an owner (its client disconnected).
  // The axes whose jog that owner held.
  homing::AxisMask release_jogs(std::uint64_t owner);
  // Taken in the next period; `wake` false leaves the wake-up to the caller
  // (wake_for_news()), which may first have answers to send.
  void set_settings(homing::Settings settings, bool wake = true);
  void wake_for_news() { waiter_->wake(); }
  // The last stops kept before this start (homing/trust.hpp), given to the
  // engine in the next period: an axis whose last stop was clean takes its
  // stored position and is offered a reference check.
  void restore_last_stops(const homing::LastStops& stops);
  void set_permit_coil(bool on);
  void raise_settings_lost();
  // The host wrote host.heartbeat (the watchdog only cares that it changes).
  void heartbeat_written(std::uint16_t value);
  // host.heartbeat changed within watchdog_ms (the caller's settings; 0:
  // no watchdog), on the live heartbeat rather than the last snapshot.
  bool heartbeat_fresh(std::uint32_t watchdog_ms) const;
  // Runs edit inside the loop and returns true once a snapshot that shows its
  // effect is published, so a read that follows sees it. False when the loop
  // did not take it within timeout: then it never runs. Without the loop
  // thread (tests and fuzzers step run_period by hand) it runs at once.
  bool edit_sim(const SimEdit& edit, std::chrono::milliseconds timeout);
  // The same without a thread waiting for it (a write of the simulator unit
  // on an event loop): done(true) is called on the loop's thread, outside
  // every lock of the loop, once a published period shows the edit; done(false)
  // when the loop stopped before taking it. Without the loop thread the edit
  // runs at once and done(true) is called before this returns. done must not
  // block: it hands the answer over.
  void edit_sim_later(SimEdit edit, std::function<void(bool shown)> done);

  Snapshot snapshot() const;
  // Its status alone: what a read of the module's registers needs, a sixth of
  // the snapshot (which carries the event ring and the simulator's view too),
  // so that readers copy less and hold the lock the loop publishes under for less.
  homing::Status status() const;
  // While the loop idles: waits until a snapshot with news beyond `after`
  // (Snapshot::news) is published, or the timeout. False on the timeout. A
  // watcher that polls the snapshot wakes when something happened instead of
  // at its own pace or at every slow tick; at the full rate it does not wait.
  bool wait_for_news(std::uint64_t after, std::chrono::milliseconds timeout);
  // The trace of the last finished homing cycle of one axis.
  AxisTrace trace(std::size_t axis) const;
  LoopStats stats() const;
  // The machine is the simulator (its backend has simulator controls).
  bool has_sim() const { return io_->simulator_controls() != nullptr; }

  // Runs one period by hand (tests step the loop without a thread).
  void run_period(double wall_dt_s);

  // One turn of the control thread: waits as the thread does, then runs the
  // period. At the full rate the wait is to the next deadline; while quiet
  // until a wake, an input event, the machine's next scheduled change, the
  // watchdog's deadline or the slow tick, whichever comes first, yet never
  // less than a period after the last one. The thread loops on it; tests
  // drive it by hand with a fake waiter. False once a requested stop has
  // come to rest (the thread then ends).
  bool run_turn();
  // The last period ended quiet: the next wait is a quiet one.
  bool quiet() const { return quiet_; }

  // The slow tick while quiet: the longest a quiet loop goes without a
  // period, so status.heartbeat, the machine time and inputs read without
  // line events still move on (and systemd's watchdog hears from it).
  static constexpr int kQuietTickMs = 50;

  // The most wall-clock time one period advances a simulated machine. A
  // period simulates the wall time since the last one times --time-scale,
  // in steps of the nominal period; when the computer cannot compute that
  // as fast as it passes (a sanitized build, several time-scaled daemons on
  // a shared machine), catching it all up would make each period longer than
  // the one before, without bound, and commands wait for the next period.
  // Beyond this the simulation falls behind the wall clock instead. Real
  // hardware is never held back: its time is the wall clock.
  static constexpr double kSimCatchUpMaxS = 0.05;

 private:
  void thread_main();
  void begin_stop_report();
  void end_stop_report(bool still_moving);
  struct Mailbox {
    homing::Commands commands{};
    bool settings_lost = false;
    std::optional<homing::LastStops> restore;
  };
  // Returns false when the server held the mailbox (its news waits a period).
  bool take_mailbox(Mailbox& out);
  // One engine step of dt_s on the machine's inputs and this mailbox.
  void step_engine(double dt_s, const Mailbox& mail);
  // When the next quiet wait must end at the latest (loop clock).
  std::int64_t quiet_deadline_ns() const;
  void record_lateness(std::int64_t late_ns);
  // global.watchdog_ms is on and host.heartbeat has not changed within it.
  bool heartbeat_stale() const;
  void record_trace(const homing::Status& status);
  // A simulated machine is wired as settings_ say (external commutators).
  void simulator_follows_settings();
  void publish_sim(Snapshot& s) const;

  homing::Settings settings_;
  std::unique_ptr<homing::MachineIo> io_;
  int period_us_;
  double time_scale_;
  std::unique_ptr<LoopWaiter> waiter_;
  homing::Engine engine_;
  homing::Outputs outputs_{};

  mutable std::mutex mailbox_mutex_;
  homing::Commands pending_{};
  bool pending_from_modbus_ = false;
  std::array<std::int8_t, homing::kAxisCount> jog_dir_{};
  std::array<std::uint64_t, homing::kAxisCount> jog_owner_{};
  bool settings_pending_ = false;
  homing::Settings new_settings_{};
  struct PendingEdit {
    const SimEdit* edit = nullptr;  // owned by the edit_sim caller, who waits for it, or by `owned`
    std::uint64_t seq = 0;
    std::shared_ptr<const SimEdit> owned{};  // edit_sim_later's
    std::function<void(bool shown)> done{};  // edit_sim_later's
  };
  std::vector<PendingEdit> sim_edits_;
  bool taking_later_edits_ = false;  // the loop thread runs and will answer edit_sim_later
  std::uint64_t next_edit_seq_ = 0;
  bool permit_coil_ = false;
  bool settings_lost_pending_ = false;
  std::optional<homing::LastStops> restore_pending_;

  // Loop-private copies of the mailbox state.
  std::vector<std::function<void(bool shown)>> edits_to_answer_;  // applied, answered once published
  std::array<std::int8_t, homing::kAxisCount> loop_jog_{};
  bool loop_permit_ = false;
  bool modbus_motion_ = false;
  bool heartbeat_stale_ = false;  // in the last engine step
  std::atomic<bool> heartbeat_stale_seen_{false};  // the same, for the threads that write the heartbeat

  std::atomic<std::uint16_t> heartbeat_value_{0};
  const Clock watchdog_clock_;
  std::atomic<std::int64_t> heartbeat_changed_ns_{0};

  TraceRecorder recorder_;
  double machine_time_s_ = 0;
  bool trace_pending_ = false;
  mutable std::mutex trace_mutex_;
  std::array<AxisTrace, homing::kAxisCount> published_trace_;  // default-initialised: see TraceSample

  std::uint64_t edits_applied_ = 0;  // loop-private: last simulator edit run

  // Loop-private: the quiet idle (run_turn).
  bool quiet_ = false;           // the last period ended quiet
  double io_quiet_for_s_ = 0;    // then: MachineIo::quiet_for_s, machine seconds
  bool turns_begun_ = false;
  std::int64_t last_period_ns_ = 0;  // loop clock: when the last period ran
  std::int64_t deadline_ns_ = 0;     // the next full-rate deadline
  std::int64_t stop_started_ns_ = 0;

  mutable std::mutex snapshot_mutex_;
  std::condition_variable edit_shown_;      // with snapshot_mutex_: snapshot_.sim_edits_applied grew
  std::condition_variable news_published_;  // with snapshot_mutex_: snapshot_.news grew while idle
  Snapshot snapshot_{};
  StatusEvents status_events_;  // the loop's own, copied into each snapshot
  LoopStats stats_{};       // published copy (under snapshot_mutex_)
  LoopStats loop_stats_{};  // the loop's own
  std::uint64_t stats_publish_tick_ = 0;
  double engine_us_ = 0;
  std::uint64_t engine_steps_ = 0;

  StopReport stop_report_{};  // written by the loop thread before it ends, read after join

  std::atomic<bool> running_{false};
  std::atomic<bool> stop_requested_{false};
  std::thread thread_;
};


}  // namespace server
