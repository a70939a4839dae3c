#include "control_loop.hpp"
#include "thread_name.hpp"

#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>

#include <cstring>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "homing/gantry.hpp"

namespace server {

std::int64_t unix_now_ms() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1000 + ts.tv_nsec / 1'000'000;
}

std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

ControlLoop::ControlLoop(const homing::Settings& settings, std::unique_ptr<homing::MachineIo> io, int period_us,
                         double time_scale, Clock watchdog_clock, std::unique_ptr<LoopWaiter> waiter)
    : settings_(settings), io_(std::move(io)), period_us_(std::max(period_us, 50)),
      time_scale_(time_scale > 0 ? time_scale : 1.0), waiter_(waiter ? std::move(waiter) : make_poll_waiter()),
      watchdog_clock_(std::move(watchdog_clock)) {
  heartbeat_changed_ns_ = watchdog_clock_();
  simulator_follows_settings();
  // A first period with no elapsed time: the engine learns the inputs' levels.
  run_period(0);
}

ControlLoop::~ControlLoop() { stop(); }

void ControlLoop::start(int rt_priority) {
  if (running_.exchange(true)) return;
  stop_requested_ = false;
  edits_to_answer_.reserve(16);  // before the thread: its answers then rarely allocate
  {
    std::lock_guard lock(mailbox_mutex_);
    taking_later_edits_ = true;
  }
  thread_ = std::thread([this] {
    name_this_thread("control");
    thread_main();
  });
  if (rt_priority > 0) {
    sched_param param{};
    param.sched_priority = rt_priority;
    if (const int rc = pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &param); rc != 0)
      spdlog::warn("--rt-priority {}: real-time scheduling refused ({}); the control loop runs at normal "
                   "priority and may be late under load (grant CAP_SYS_NICE or set rtprio in limits.conf)",
                   rt_priority, std::strerror(rc));
    else
      spdlog::info("control loop: SCHED_FIFO priority {}", rt_priority);
  }
}

void ControlLoop::stop() {
  if (!running_) return;
  stop_requested_ = true;
  waiter_->wake();
  if (thread_.joinable()) thread_.join();
  running_ = false;
  // Writes still waiting for the loop are answered: applied ones as shown
  // (they were), the others as not taken.
  std::vector<std::function<void(bool)>> not_taken;
  {
    std::lock_guard lock(mailbox_mutex_);
    taking_later_edits_ = false;
    for (PendingEdit& e : sim_edits_)
      if (e.done) not_taken.push_back(std::move(e.done));
    std::erase_if(sim_edits_, [](const PendingEdit& e) { return e.owned != nullptr; });
  }
  if (!edits_to_answer_.empty())
    for (auto& done : std::exchange(edits_to_answer_, {})) done(true);
  for (auto& done : not_taken) done(false);
}

// Every piece of mailbox news wakes a quiet loop: it is taken in the period
// that follows (at the full rate the loop is not waiting: the next period
// takes it anyway). The wake comes after the lock is released, so the woken
// loop finds the mailbox free.
void ControlLoop::submit(const homing::Commands& c, bool from_modbus) {
  {
    std::lock_guard lock(mailbox_mutex_);
    homing::merge(pending_, c);
    pending_from_modbus_ = pending_from_modbus_ || from_modbus;
  }
  waiter_->wake();
}

void ControlLoop::set_jog(std::size_t axis, std::int8_t direction, std::uint64_t owner) {
  {
    std::lock_guard lock(mailbox_mutex_);
    // Who may stop it is the service's to judge (jog_buttons.hpp).
    jog_dir_[axis] = direction;
    jog_owner_[axis] = owner;
    if (direction != 0) pending_from_modbus_ = true;
  }
  waiter_->wake();
}

homing::AxisMask ControlLoop::release_jogs(std::uint64_t owner) {
  homing::AxisMask released = 0;
  {
    std::lock_guard lock(mailbox_mutex_);
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (jog_dir_[a] != 0 && jog_owner_[a] == owner) {
        jog_dir_[a] = 0;
        released |= homing::axis_bit(a);
      }
  }
  waiter_->wake();
  return released;
}

void ControlLoop::set_settings(homing::Settings settings, bool wake) {
  {
    std::lock_guard lock(mailbox_mutex_);
    new_settings_ = std::move(settings);
    settings_pending_ = true;
  }
  if (wake) waiter_->wake();
}

void ControlLoop::restore_last_stops(const homing::LastStops& stops) {
  {
    std::lock_guard lock(mailbox_mutex_);
    restore_pending_ = stops;
  }
  waiter_->wake();
}

void ControlLoop::set_permit_coil(bool on) {
  {
    std::lock_guard lock(mailbox_mutex_);
    permit_coil_ = on;
  }
  waiter_->wake();
}

void ControlLoop::raise_settings_lost() {
  {
    std::lock_guard lock(mailbox_mutex_);
    settings_lost_pending_ = true;
  }
  waiter_->wake();
}

void ControlLoop::heartbeat_written(std::uint16_t value) {
  if (heartbeat_value_.exchange(value) == value) return;
  heartbeat_changed_ns_ = watchdog_clock_();
  // A heartbeat back after the watchdog expired: status.interlocks clears in
  // the next period, not at the quiet loop's next tick.
  if (heartbeat_stale_seen_.load(std::memory_order_relaxed)) waiter_->wake();
}

bool ControlLoop::edit_sim(const SimEdit& edit, std::chrono::milliseconds timeout) {
  homing::sim::SimulatorControls* sim = io_->simulator_controls();
  if (!sim) return false;
  if (!running_) {
    // Stepped by hand: the caller is the only one running the loop.
    std::lock_guard mail(mailbox_mutex_);
    edit(*sim, outputs_);
    std::lock_guard lock(snapshot_mutex_);
    publish_sim(snapshot_);
    return true;
  }
  std::uint64_t seq = 0;
  {
    std::lock_guard lock(mailbox_mutex_);
    seq = ++next_edit_seq_;
    sim_edits_.push_back(PendingEdit{&edit, seq});
  }
  waiter_->wake();  // a quiet loop runs it at once: the answer comes within a period
  auto shown = [&] { return snapshot_.sim_edits_applied >= seq; };
  {
    std::unique_lock lock(snapshot_mutex_);
    if (edit_shown_.wait_for(lock, timeout, shown)) return true;
  }
  {
    // Not shown in time: withdraw it if the loop has not taken it yet. The loop
    // runs edits holding this lock, so once it is ours a taken edit has run.
    std::lock_guard lock(mailbox_mutex_);
    const auto it = std::find_if(sim_edits_.begin(), sim_edits_.end(),
                                 [&](const PendingEdit& p) { return p.seq == seq; });
    if (it != sim_edits_.end()) {
      sim_edits_.erase(it);
      return false;
    }
  }
  std::unique_lock lock(snapshot_mutex_);
  edit_shown_.wait_for(lock, timeout, shown);
  return true;
}

void ControlLoop::edit_sim_later(SimEdit edit, std::function<void(bool shown)> done) {
  homing::sim::SimulatorControls* sim = io_->simulator_controls();
  if (!sim) {
    done(false);
    return;
  }
  {
    std::unique_lock mail(mailbox_mutex_);
    if (!taking_later_edits_) {
      // Stepped by hand (or stopped): the caller is the only one running the loop.
      edit(*sim, outputs_);
      std::lock_guard lock(snapshot_mutex_);
      publish_sim(snapshot_);
    } else {
      sim_edits_.push_back(
          PendingEdit{nullptr, ++next_edit_seq_, std::make_shared<const SimEdit>(std::move(edit)), std::move(done)});
      sim_edits_.back().edit = sim_edits_.back().owned.get();
      mail.unlock();
      waiter_->wake();  // a quiet loop runs it at once: the answer comes within a period
      return;
    }
  }
  done(true);
}

void ControlLoop::simulator_follows_settings() {
  if (homing::sim::SimulatorControls* sim = io_->simulator_controls()) sim->follow_settings(settings_);
}

double LoopStats::lateness_percentile_us(double q) const {
  std::uint64_t total = 0;
  for (auto n : lateness_us_histogram) total += n;
  if (total == 0) return 0;
  const auto wanted = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(total)));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < kBuckets; ++i) {
    seen += lateness_us_histogram[i];
    if (seen >= wanted) return i == kBuckets - 1 ? max_lateness_us : static_cast<double>(i);
  }
  return max_lateness_us;
}

Snapshot ControlLoop::snapshot() const {
  std::lock_guard lock(snapshot_mutex_);
  return snapshot_;
}

homing::Status ControlLoop::status() const {
  std::lock_guard lock(snapshot_mutex_);
  return snapshot_.status;
}

LoopStats ControlLoop::stats() const {
  std::lock_guard lock(snapshot_mutex_);
  return stats_;
}

// Never blocks: when the server holds the mailbox, its news waits one period.
// Taken before the machine advances, so that a simulator edit (a carriage
// placed, a fault) is already in the inputs the commands are judged on.
bool ControlLoop::take_mailbox(Mailbox& out) {
  std::unique_lock lock(mailbox_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return false;
  out.commands = pending_;
  if (pending_from_modbus_ && (pending_.home_all || pending_.home_axes || pending_.move_axes || pending_.refcheck_axes ||
                               pending_.measure_axes))
    modbus_motion_ = true;
  pending_ = homing::Commands{};
  pending_from_modbus_ = false;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    if (jog_dir_[a] != 0 && loop_jog_[a] == 0) modbus_motion_ = true;
    loop_jog_[a] = jog_dir_[a];
  }
  if (settings_pending_) {
    settings_ = new_settings_;
    settings_pending_ = false;
    simulator_follows_settings();
  }
  if (homing::sim::SimulatorControls* sim = io_->simulator_controls()) {
    for (PendingEdit& e : sim_edits_) {
      (*e.edit)(*sim, outputs_);
      edits_applied_ = e.seq;
      if (e.done) edits_to_answer_.push_back(std::move(e.done));
    }
  }
  sim_edits_.clear();
  loop_permit_ = permit_coil_;
  out.settings_lost = settings_lost_pending_;
  settings_lost_pending_ = false;
  out.restore = restore_pending_;
  restore_pending_.reset();
  return true;
}

bool ControlLoop::heartbeat_stale() const { return !heartbeat_fresh(settings_.global.watchdog_ms); }

bool ControlLoop::heartbeat_fresh(std::uint32_t watchdog_ms) const {
  if (watchdog_ms == 0) return true;
  return watchdog_clock_() - heartbeat_changed_ns_.load() <= std::int64_t{watchdog_ms} * 1'000'000;
}

void ControlLoop::run_period(double wall_dt_s) {
  // --time-scale: several engine periods of the nominal length per wall
  // period, so precision does not change with the speed-up.
  const bool held_back = wall_dt_s > kSimCatchUpMaxS && has_sim();
  if (held_back) ++loop_stats_.sim_held_back_periods;
  const double sim_dt = (held_back ? kSimCatchUpMaxS : wall_dt_s) * time_scale_;
  const double nominal = period_us_ * 1e-6;
  const int steps = sim_dt <= 0 ? 1 : std::max(1, static_cast<int>(std::ceil(sim_dt / nominal - 1e-9)));
  const double dt = sim_dt / steps;
  bool mailbox_taken = false;
  for (int i = 0; i < steps; ++i) {
    Mailbox mail;
    if (i == 0) mailbox_taken = take_mailbox(mail);
    step_engine(dt, mail);
  }
  if (trace_pending_) {
    std::unique_lock trace_lock(trace_mutex_, std::try_to_lock);
    if (trace_lock.owns_lock()) {
      published_trace_ = recorder_.traces();
      trace_pending_ = false;
    }
  }
  loop_stats_.engine_us_total = engine_us_;
  loop_stats_.engine_steps = engine_steps_;
  ++loop_stats_.periods;
  // Quiet only when this period left nothing behind: its mailbox taken, its
  // trace and snapshot published (else the next period, at the full rate,
  // does it), and neither the engine nor the machine has anything under way.
  const bool may_rest = mailbox_taken && !trace_pending_ && !stop_requested_ && engine_.quiet();
  const double io_quiet_for_s = may_rest ? io_->quiet_for_s(outputs_) : 0;
  quiet_ = false;
  io_quiet_for_s_ = 0;
  std::unique_lock lock(snapshot_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;  // a reader is copying: publish next period
  io_quiet_for_s_ = io_quiet_for_s;
  quiet_ = io_quiet_for_s > 0;
  Snapshot& s = snapshot_;
  const std::uint32_t commands_before = s.status.command_count;
  s.status = engine_.status();
  s.outputs = outputs_;
  s.periods = loop_stats_.periods;
  const bool events_shown = s.events.written() != status_events_.written();
  if (events_shown) s.events = status_events_;  // rare: no copy per period
  // The histogram is 32 KiB: copied now and then, and in every quiet period
  // (a few a second), so the figures are current while idle.
  if (++stats_publish_tick_ % 64 == 0 || quiet_) stats_ = loop_stats_;
  publish_sim(s);
  const bool edits_shown = s.sim_edits_applied != edits_applied_;
  s.sim_edits_applied = edits_applied_;
  // What the watcher acts on: motion, an event (an alarm, a cycle), a
  // command judged. A simulator edit is none: its writer waits for it alone,
  // and the watcher keeps a carriage it placed at its next look.
  const bool news = !quiet_ || !s.quiet || events_shown || s.status.command_count != commands_before;
  if (news) ++s.news;
  // Idle periods with news and the first one after: a watcher of the idle
  // loop (wait_for_news) waits for these.
  const bool idle_news = news && (s.quiet || quiet_);
  s.quiet = quiet_;
  lock.unlock();
  if (edits_shown) edit_shown_.notify_all();  // a simulator write waits for this
  // Published: the writes handed over are answered (outside every lock: each
  // hands its answer to its event loop).
  if (!edits_to_answer_.empty()) {
    for (auto& done : edits_to_answer_) done(true);
    edits_to_answer_.clear();  // keeps its capacity (each answer's own hand-over still allocates a little)
  }
  if (idle_news) news_published_.notify_all();
}

bool ControlLoop::wait_for_news(std::uint64_t after, std::chrono::milliseconds timeout) {
  std::unique_lock lock(snapshot_mutex_);
  return news_published_.wait_for(lock, timeout, [&] { return snapshot_.news > after || !snapshot_.quiet; });
}

void ControlLoop::step_engine(double dt, const Mailbox& mail) {
  io_->advance(outputs_, dt);
  homing::Inputs inputs = io_->read();
  inputs.commands = mail.commands;
  inputs.commands.jog = loop_jog_;
  inputs.homing_permit = inputs.homing_permit || loop_permit_;
  inputs.settings_lost = mail.settings_lost;
  inputs.restore = mail.restore;
  // Stale, moving or not, is what the interlock shows and what a reset is
  // refused for; lost is what stops motion started over Modbus.
  inputs.heartbeat_stale = heartbeat_stale_ = heartbeat_stale();
  heartbeat_stale_seen_.store(heartbeat_stale_, std::memory_order_relaxed);
  inputs.communication_lost = heartbeat_stale_ && modbus_motion_;
  const std::int64_t t0 = monotonic_ns();
  const homing::StepResult r = engine_.step(settings_, inputs, dt);
  const std::int64_t t1 = monotonic_ns();
  outputs_ = r.outputs;
  io_->apply(outputs_);  // real hardware plays them from the instant the period began
  machine_time_s_ += dt;
  record_trace(r.status);
  status_events_.observe(r.status, unix_now_ms());
  const bool motion = r.status.homing || r.status.state == homing::MachineState::moving;
  if (!motion && !inputs.commands.home_all && !inputs.commands.home_axes && !inputs.commands.move_axes &&
      !inputs.commands.refcheck_axes && !inputs.commands.measure_axes &&
      std::none_of(loop_jog_.begin(), loop_jog_.end(), [](std::int8_t j) { return j != 0; }))
    modbus_motion_ = false;
  engine_us_ += (t1 - t0) / 1000.0;
  ++engine_steps_;
}

void ControlLoop::publish_sim(Snapshot& s) const {
  const homing::sim::SimulatorControls* sim = io_->simulator_controls();
  if (!sim) return;
  s.has_sim = true;
  s.sim = sim->view();
  s.machine_time_s = s.sim.time_s;
}

void ControlLoop::record_trace(const homing::Status& status) {
  std::array<double, homing::kAxisCount> motor{};
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) motor[a] = outputs_.axes[a].motor.position_mm;
  if (status.homing) {
    if (!recorder_.active()) recorder_.begin(period_us_ * 1e-6);
    recorder_.record(machine_time_s_, status, motor);
  } else if (recorder_.active()) {
    recorder_.finish(machine_time_s_, status, motor);
    trace_pending_ = true;
  }
}

AxisTrace ControlLoop::trace(std::size_t axis) const {
  std::lock_guard lock(trace_mutex_);
  return published_trace_[axis];
}

// The engine's own state, not the snapshot: a reader holding the snapshot
// lock may have kept the last period from being published.
void ControlLoop::begin_stop_report() {
  stop_report_ = StopReport{};
  stop_report_.machine_s = machine_time_s_;
  const homing::Status& st = engine_.status();
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    StopReport::Axis& r = stop_report_.axes[a];
    r.velocity_mm_per_s = st.axes[a].velocity_mm_per_s;
    r.moving = r.velocity_mm_per_s != 0;
    r.from_mm = st.axes[a].position_mm;
    r.unit = homing::axis_unit(settings_, a);
  }
}

void ControlLoop::end_stop_report(bool still_moving) {
  stop_report_.machine_s = machine_time_s_ - stop_report_.machine_s;
  stop_report_.at_rest = !still_moving;
  const homing::Status& st = engine_.status();
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) stop_report_.axes[a].rest_mm = st.axes[a].position_mm;
  stop_report_.last_stops = homing::last_stops_at_shutdown(settings_, st, outputs_);
  if (still_moving)
    for (homing::LastStop& s : stop_report_.last_stops) s.clean = false;
  if (const homing::sim::SimulatorControls* sim = io_->simulator_controls()) {
    const homing::sim::SimulatorView view = sim->view();
    std::array<double, homing::kAxisCount> at{};
    for (std::size_t a = 0; a < homing::kAxisCount; ++a) at[a] = view.axes[a].actual_position_mm;
    stop_report_.sim_carriages_mm = at;
  }
}

void ControlLoop::thread_main() {
  while (run_turn()) {}
  io_->shutdown();
}

std::int64_t ControlLoop::quiet_deadline_ns() const {
  std::int64_t until = last_period_ns_ + std::int64_t{kQuietTickMs} * 1'000'000;
  // The machine's next scheduled change (a time-scaled simulator's seconds
  // pass faster than the wall clock's).
  const double io_wall_s = io_quiet_for_s_ / time_scale_;
  if (io_wall_s < kQuietTickMs * 1e-3) until = std::min<std::int64_t>(until, last_period_ns_ + std::llround(io_wall_s * 1e9));
  // The watchdog: communication_lost shows in the period its deadline passes
  // (once shown, nothing is left to wait for until a heartbeat or a command).
  const std::uint32_t ms = settings_.global.watchdog_ms;
  if (ms != 0 && !heartbeat_stale_) {
    const std::int64_t left_ns = heartbeat_changed_ns_.load() + std::int64_t{ms} * 1'000'000 + 1 - watchdog_clock_();
    until = std::min(until, waiter_->now_ns() + std::max<std::int64_t>(left_ns, 0));
  }
  return until;
}

void ControlLoop::record_lateness(std::int64_t late_ns) {
  // Loop-private figures: published with the snapshot, never behind a lock here.
  const double lateness_us = late_ns / 1000.0;
  loop_stats_.max_lateness_us = std::max(loop_stats_.max_lateness_us, lateness_us);
  const auto bucket = static_cast<std::size_t>(std::clamp(lateness_us, 0.0, double(LoopStats::kBuckets - 1)));
  ++loop_stats_.lateness_us_histogram[bucket];
  if (late_ns > std::int64_t{period_us_} * 1000) ++loop_stats_.late_periods;
}

bool ControlLoop::run_turn() {
  const std::int64_t period_ns = std::int64_t{period_us_} * 1000;
  if (!turns_begun_) {
    turns_begun_ = true;
    last_period_ns_ = waiter_->now_ns();
    deadline_ns_ = last_period_ns_ + period_ns;
  }
  const bool quiet_wait = quiet_ && !stop_requested_;
  std::int64_t now = 0;
  if (quiet_wait) {
    const std::int64_t until = quiet_deadline_ns();
    const bool woken = waiter_->wait_until(until, io_->event_fds());
    now = waiter_->now_ns();
    // Never sooner than a period after the last: the engine plans what the
    // wake brings on a period of the nominal length at least.
    if (now < last_period_ns_ + period_ns) {
      waiter_->sleep_until(last_period_ns_ + period_ns);
      now = waiter_->now_ns();
    }
    ++loop_stats_.quiet_periods;
    if (woken) ++loop_stats_.woken_periods;
    else record_lateness(now - std::max(until, last_period_ns_ + period_ns));
  } else {
    waiter_->sleep_until(deadline_ns_);
    now = waiter_->now_ns();
    record_lateness(now - deadline_ns_);
  }
  if (stop_requested_ && stop_started_ns_ == 0) {
    // Stop safely: abort whatever moves, let it decelerate, then leave.
    homing::Commands abort{};
    abort.abort = true;
    submit(abort, false);
    stop_started_ns_ = now;
    begin_stop_report();
  }
  if (stop_started_ns_ != 0) {
    // Nothing starts moving again while the stop runs.
    std::lock_guard lock(mailbox_mutex_);
    jog_dir_.fill(0);
    pending_.home_all = false;
    pending_.home_axes = 0;
    pending_.move_axes = 0;
    pending_.refcheck_axes = 0;
    pending_.measure_axes = 0;
  }
  const double wall_dt_s = (now - last_period_ns_) * 1e-9;
  const double nominal_s = period_us_ * 1e-6;
  if (quiet_wait && wall_dt_s >= 2 * nominal_s) {
    // The stretch was quiet: the machine ran outputs of rest and nothing was
    // scheduled in it. One engine step covers it, with no mailbox (a
    // time-scaled simulator is not held back for it: there is nothing to
    // compute), then the period proper runs with its nominal length, so the
    // engine plans whatever the wake brought on a period's dt, not the
    // stretch's (its look-aheads and braking use the last dt).
    step_engine((wall_dt_s - nominal_s) * time_scale_, Mailbox{});
    run_period(nominal_s);
  } else {
    run_period(wall_dt_s);
  }
  last_period_ns_ = now;
  if (stop_started_ns_ != 0) {
    const Snapshot s = snapshot();
    bool moving = false;
    for (const auto& a : s.status.axes) moving = moving || a.velocity_mm_per_s != 0;
    if (!moving || now - stop_started_ns_ > 10'000'000'000LL) {
      end_stop_report(moving);
      return false;
    }
  }
  if (quiet_wait) {
    deadline_ns_ = now + period_ns;  // the full-rate deadlines start again from this period
  } else {
    deadline_ns_ += period_ns;
    if (now - deadline_ns_ > period_ns) deadline_ns_ = now + period_ns;  // far behind: do not burst
  }
  return true;
}

}  // namespace server
