#include "monitor.hpp"
#include "thread_name.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "health_trend.hpp"
#include "homing/gantry.hpp"

namespace server {

std::int64_t unix_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Monitor::Monitor(ControlLoop& loop, ModbusService& service, persistence::SettingsStore* store,
                 std::function<std::uint32_t()> tcp_clients)
    : loop_(loop), service_(service), store_(store), tcp_clients_(std::move(tcp_clients)) {}

namespace {

std::uint64_t resident_kb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::strtoull(line.c_str() + 6, nullptr, 10);
  return 0;
}

persistence::AxisHealth history_figures(const homing::SwitchHealth& h) {
  persistence::AxisHealth f;
  f.latch_passes = h.latch_passes;
  f.latch_spread_mm = h.latch_spread_mm;
  f.latch_sigma_mm = h.latch_sigma_mm;
  f.hysteresis_mm = h.hysteresis_mm;
  f.seek_latch_mm = h.seek_latch_mm;
  f.chatter_edges = h.chatter_edges;
  f.index_distance_mm = h.index_distance_mm;
  f.index_near_edge = h.index_near_edge;
  if (h.gantry_skew_measured) f.gantry_skew_mm = h.gantry_skew_mm;
  return f;
}

}  // namespace

// Only a cycle that starts from a position the module trusts measures
// anything: the first cycle after a start-up corrects by wherever the axis
// stood (84 mm with a good sensor), which would make the sensor look broken.
persistence::AxisRun axis_record(bool cycle_ok, const homing::AxisStatus& axis, std::int64_t duration_ms) {
  persistence::AxisRun r;
  r.present = true;
  r.duration_ms = duration_ms;
  if (!cycle_ok) r.excluded = persistence::Excluded::cycle_failed;
  else if (!axis.homed_at_cycle_start) r.excluded = persistence::Excluded::not_homed_before;
  else r.correction_mm = axis.home_correction_mm;
  // Its figures describe the reference it found; a cycle that ended before
  // (or with an alarm on it) measured nothing to trend.
  if (axis.homed && !axis.alarm) {
    r.health = history_figures(axis.health);
    // A gantry's skew measures how far the pair racked since it was last
    // squared only when it was homed then: the first cycle after a start-up
    // finds the carriages wherever they were left (it is published, not kept).
    if (!axis.homed_at_cycle_start) r.health->gantry_skew_mm.reset();
  }
  return r;
}

void Monitor::refresh_diagnostics() {
  const LoopStats s = loop_.stats();
  extras_.loop_periods = s.periods;
  extras_.late_p50_us = s.lateness_percentile_us(0.50);
  extras_.late_p99_us = s.lateness_percentile_us(0.99);
  extras_.late_p999_us = s.lateness_percentile_us(0.999);
  extras_.late_max_us = s.max_lateness_us;
  extras_.engine_step_ns = s.engine_steps ? s.engine_us_total * 1000.0 / static_cast<double>(s.engine_steps) : 0;
  if (s.sim_held_back_periods > 0 && !sim_behind_logged_) {
    sim_behind_logged_ = true;
    spdlog::warn("the simulated machine fell behind the wall clock: a control period came more than {:.0f} ms after "
                 "the last (the computer too busy for --time-scale, engine step {:.0f} us, or the process stopped); "
                 "the simulation catches up no more than that in one period, so it ran slower than asked",
                 ControlLoop::kSimCatchUpMaxS * 1000, extras_.engine_step_ns / 1000.0);
  }
  extras_.rss_kb = resident_kb();
  extras_.tcp_clients = tcp_clients_ ? tcp_clients_() : 0;
}

// Twice a second: diagnostics for the input registers, the refused writes'
// counts of an interval that has passed, the settings backup that the store
// keeps after a batch of changes and the WAL checkpoint (both beside the
// writer, so no settings write waits for them).
// The idle monitor's next look without news: its housekeeping, or sooner
// the carriages it could not keep yet.
std::chrono::milliseconds Monitor::until_next_look(std::int64_t now_ms) const {
  std::int64_t at = last_housekeeping_ms_ + kHousekeepingMs;
  if (carriages_due_ms_) at = std::min(at, *carriages_due_ms_);
  return std::chrono::milliseconds(std::clamp<std::int64_t>(at - now_ms, 1, kHousekeepingMs));
}

void Monitor::housekeeping(std::int64_t now_ms) {
  if (now_ms - last_housekeeping_ms_ < kHousekeepingMs) return;
  last_housekeeping_ms_ = now_ms;
  refresh_diagnostics();
  service_.set_extras(extras_);
  service_.flush_refusal_log();
  service_.flush_edit_sessions();
  if (store_) {
    const auto note = [now_ms](RecurringWarning& w, const persistence::Status& r) {
      if (r) w.worked(now_ms);
      else w.failed(now_ms, r.error().message);
    };
    note(backup_warning_, store_->backup_if_due());
    note(checkpoint_warning_, store_->checkpoint());
    // The audit log's bound, kept here rather than on a write's path.
    note(prune_warning_, store_->prune_audit());
  }
  if (events_) events_->settings_changes();
}

Monitor::~Monitor() { stop(); }

void Monitor::start() {
  // The warnings the stored history gives already: a restart does not hide them.
  const homing::Settings settings = service_.settings();
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) judge_health(a, settings);
  refresh_summary();
  thread_ = std::thread([this] {
    name_this_thread("monitor");
    while (!stop_) {
      poll(unix_ms());
      // While the loop idles nothing changes until something comes: the next
      // look comes with the loop's next news (a command, an input edge, an
      // alarm) or with the housekeeping, so an idle daemon's monitor wakes
      // twice a second, not at every slow tick.
      if (last_quiet_) loop_.wait_for_news(last_news_, until_next_look(unix_ms()));
      else std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  });
}

void Monitor::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void Monitor::refresh_summary() {
  if (!store_) return;
  registers::StatusExtras& extras = extras_;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    if (auto s = store_->correction_summary(a, 10); s && s->count > 0) {
      extras.correction_mean_mm[a] = s->mean;
      extras.correction_spread_mm[a] = s->spread;
    }
  }
  service_.set_extras(extras_);
}

// The trend of the axis's last cycles in the history: its warning is
// published, and logged once each time it changes.
void Monitor::judge_health(std::size_t axis, const homing::Settings& settings) {
  if (!store_) return;
  const TrendSettings t = trend_settings(settings, axis);
  auto records = store_->health_history(axis, std::max<std::size_t>(t.cycles, 1));
  if (!records) {
    spdlog::error("health trend of {} not judged: {}", homing::kAxisUpper[axis], records.error().message);
    return;
  }
  std::vector<persistence::AxisHealth> figures;
  for (const auto& r : *records) figures.push_back(r.health);
  const auto verdicts = judge_trend(figures, t);
  const homing::HealthWarning now = verdicts.empty() ? homing::HealthWarning::none : verdicts.front().warning;
  homing::HealthWarning& shown = extras_.health_warning[axis];
  if (now == shown) return;
  if (now == homing::HealthWarning::none)
    spdlog::info("health warning {} on {} cleared", homing::name_of(shown), homing::kAxisUpper[axis]);
  else
    spdlog::warn("health warning {} on {} (not an alarm: the axis stays homed): {}", homing::name_of(now),
                 homing::kAxisUpper[axis], verdict_text(verdicts.front(), settings, axis));
  shown = now;
}

void Monitor::poll(std::int64_t now_ms) {
  const Snapshot snap = loop_.snapshot();
  const homing::Status& st = snap.status;
  last_news_ = snap.news;
  last_quiet_ = snap.quiet;
  if (first_) {
    // Nothing to report of the state at start, except an alarm already
    // latched (settings_lost, an e-stop pressed): it is logged like any other.
    last_ = st;
    last_.global_alarm = homing::AlarmCode::none;
    for (auto& axis : last_.axes) axis.alarm = homing::Alarm{};
    first_ = false;
  }
  const homing::Settings settings = service_.settings();
  if (events_) events_->take(snap.events, settings);
  // After the loop's events: a settings change read now comes after every
  // cycle and alarm this snapshot holds, which may be older than it (this
  // thread late on a busy machine); the plant gets them in the order they happened.
  housekeeping(now_ms);
  log_alarms(snap.events, settings);
  if (st.alarm != last_.alarm && !st.alarm) spdlog::info("alarms reset");
  // Every command judged since the last look, also one whose result equals
  // the one before (two accepted commands in a row, a jog after a home);
  // several judged between two looks are one line with the last one's result.
  if (const std::uint32_t judged = st.command_count - last_.command_count; judged > 1)
    spdlog::info("command result: {} (the last of {} commands)", homing::command_result_name(st.last_command_result),
                 judged);
  else if (judged == 1 || st.last_command_result != last_.last_command_result || st.heartbeat == 0)
    spdlog::info("command result: {}", homing::command_result_name(st.last_command_result));
  if (!st.homing && !last_.homing) record_unseen_cycle(snap, settings);
  if (st.homing && !last_.homing) {
    run_start_ms_ = now_ms;
    run_axes_ = 0;
    for (std::size_t a = 0; a < homing::kAxisCount; ++a) measured_at_start_[a] = st.axes[a].measurement;
    spdlog::info(st.reference_check ? "reference check started" : "homing started");
  }
  if (st.homing) {
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (st.axes[a].busy) run_axes_ |= homing::axis_bit(a);
  }
  if (!st.homing && last_.homing) {
    // The loop saw every period of the cycle: its axes come from the cycle's
    // end event too, so a cycle shorter than a few of this thread's looks
    // (a busy machine, 50 ms at --time-scale 10) still records all its axes.
    // Its result too: an alarm reset a moment after the cycle ended (a PLC
    // that resets at once) is gone from this snapshot, not from the event.
    const StatusEvent* ended = nullptr;
    for (std::uint64_t seq = snap.events.written(); seq > cycle_events_taken_; --seq) {
      const StatusEvent* e = snap.events.find(seq);
      if (!e) break;
      if (e->kind != StatusEventKind::cycle_ended) continue;
      run_axes_ |= e->axes;
      ended = e;
      break;
    }
    cycle_events_taken_ = snap.events.written();
    // A reference check is no homing cycle: it measured nothing of the switch
    // to keep in the history, only whether the axis is where it was kept.
    if (last_.reference_check) report_refcheck(st, settings);
    else record_run(st, ended, settings, now_ms);
    report_measurements(st, settings);
  }
  for (std::size_t a = 0; a < homing::kAxisCount; ++a)
    if (st.axes[a].positions_set != last_.axes[a].positions_set)
      service_.audit_position_set(a, last_.axes[a].position_mm, st.axes[a].position_mm);
  keep_sim_carriages(snap, now_ms);
  last_ = st;
}

// A cycle that started and ended between two looks of this thread (a short
// cycle, this thread late on a busy machine): the loop's events hold it whole.
void Monitor::record_unseen_cycle(const Snapshot& snap, const homing::Settings& settings) {
  const StatusEvent* ended = nullptr;
  for (std::uint64_t seq = cycle_events_taken_ + 1; seq <= snap.events.written(); ++seq)
    if (const StatusEvent* e = snap.events.find(seq); e && e->kind == StatusEventKind::cycle_ended) ended = e;
  cycle_events_taken_ = snap.events.written();
  if (!ended) return;
  run_start_ms_ = ended->time_ms - ended->duration_ms;
  run_axes_ = ended->axes;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) measured_at_start_[a] = last_.axes[a].measurement;
  spdlog::info("homing started");
  record_run(snap.status, ended, settings, ended->time_ms);
  report_measurements(snap.status, settings);
}

void Monitor::record_run(const homing::Status& st, const StatusEvent* ended, const homing::Settings& settings,
                         std::int64_t now_ms) {
  persistence::HomingRun run;
  run.start_ms = run_start_ms_;
  run.end_ms = now_ms;
  run.axes = run_axes_;
  run.result = 0;
  if (ended) {
    run.result = static_cast<int>(ended->code);
    if (ended->axis >= 0) run.alarm_axis = ended->axis;
  } else {  // the ring moved on past it (this thread very late): the snapshot is all there is
    if (const int a = homing::reported_alarm_axis(st); a >= 0) {
      run.result = static_cast<int>(st.axes[static_cast<std::size_t>(a)].alarm.code);
      run.alarm_axis = a;
    }
    if (run.result == 0 && st.global_alarm != homing::AlarmCode::none) run.result = static_cast<int>(st.global_alarm);
  }
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    if (!(run_axes_ & homing::axis_bit(a))) continue;
    run.axis[a] = axis_record(run.result == 0, st.axes[a], now_ms - run_start_ms_);
    if (run.axis[a].excluded == persistence::Excluded::not_homed_before)
      spdlog::info("home correction of {} not counted in its statistics: {} ({:+.3f} {} is where it stood)",
                   homing::kAxisUpper[a], persistence::excluded_text(run.axis[a].excluded),
                   st.axes[a].home_correction_mm, homing::axis_unit(settings, a));
  }
  if (run.result == 0) spdlog::info("homing done in {} ms", now_ms - run_start_ms_);
  else spdlog::warn("homing ended with alarm {}", homing::alarm_name(static_cast<homing::AlarmCode>(run.result)));
  if (store_)
    if (auto r = store_->record_homing_run(run); !r) spdlog::error("history not recorded: {}", r.error().message);
  for (std::size_t a = 0; a < homing::kAxisCount; ++a)
    if (run.axis[a].health) judge_health(a, settings);
  refresh_summary();
}

// Every alarm the loop saw raised since the last look, from its events: one
// raised and reset between two looks of this thread is logged all the same.
void Monitor::log_alarms(const StatusEvents& events, const homing::Settings& settings) {
  const std::uint64_t written = events.written();
  std::uint64_t missed = 0;
  for (std::uint64_t seq = alarm_events_taken_ + 1; seq <= written; ++seq) {
    const StatusEvent* e = events.find(seq);
    if (!e) {
      ++missed;
      continue;
    }
    if (e->kind != StatusEventKind::alarm_raised) continue;
    if (e->axis >= 0)
      spdlog::error("alarm {} ({}): {}", static_cast<int>(e->code), homing::alarm_name(e->code),
                    homing::describe_alarm(static_cast<std::size_t>(e->axis), e->alarm, settings));
    else
      spdlog::error("alarm {}: {}", homing::alarm_name(e->code), homing::describe_global_alarm(e->code, settings));
  }
  if (missed > 0) spdlog::warn("{} status events passed before the monitor saw them; their alarms are not in the log", missed);
  alarm_events_taken_ = written;
}

// Each axis checked: accepted and homed, or refused with the figure (an
// alarm that stopped the check is logged as every alarm is).
void Monitor::report_refcheck(const homing::Status& st, const homing::Settings& settings) {
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    if (!(run_axes_ & homing::axis_bit(a))) continue;
    const homing::AxisStatus& x = st.axes[a];
    const auto unit = homing::axis_unit(settings, a);
    const double tolerance = settings.axes[a].refcheck_tolerance_mm;
    if (x.alarm || st.global_alarm != homing::AlarmCode::none)
      spdlog::warn("reference check of {} stopped by an alarm: {} is not homed", homing::kAxisUpper[a],
                   homing::kAxisUpper[a]);
    else if (x.trust == homing::Trust::reference_checked)
      spdlog::info("reference check of {} accepted: its switch edge lies {:+.3f} {} from where its stored position "
                   "put it (tolerance {:.3f} {}); {} is homed",
                   homing::kAxisUpper[a], x.refcheck_error_mm, unit, tolerance, unit, homing::kAxisUpper[a]);
    else
      spdlog::warn("reference check of {} refused: its switch edge lies {:+.3f} {} from where its stored position "
                   "put it (tolerance {:.3f} {}): the carriage moved or lost steps while the module was off, or its "
                   "switch moved; home {} with a full cycle",
                   homing::kAxisUpper[a], x.refcheck_error_mm, unit, tolerance, unit, homing::kAxisUpper[a]);
  }
}

// The simulator keeps its carriages across a restart, as a real machine
// does, even one that ends without a clean shutdown: each time they come to
// rest somewhere new (a cycle, a jog, a carriage placed: seen at the next
// look, half a second at most), at most 5 times a second.
void Monitor::keep_sim_carriages(const Snapshot& snap, std::int64_t now_ms) {
  carriages_due_ms_.reset();
  if (!store_ || !snap.has_sim) return;
  std::array<double, homing::kAxisCount> at{};
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    if (snap.sim.axes[a].moving) return;
    at[a] = snap.sim.axes[a].actual_position_mm;
  }
  if (carriages_kept_ == at) return;
  if (now_ms - carriages_kept_ms_ < kCarriagesMinGapMs) {
    carriages_due_ms_ = carriages_kept_ms_ + kCarriagesMinGapMs;  // the idle monitor looks again then
    return;
  }
  carriages_kept_ms_ = now_ms;
  if (auto r = store_->record_sim_carriages(at); !r) {
    spdlog::warn("simulator carriages not kept: {}", r.error().message);
    return;
  }
  carriages_kept_ = at;
}

// A measurement's figures, at the end of the cycle that found them.
void Monitor::report_measurements(const homing::Status& st, const homing::Settings& settings) {
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const homing::Measurement& m = st.axes[a].measurement;
    // A measurement resets its axis's figures as it starts: new ones differ from those at the start.
    if (m.usable_travel_mm == 0 || m.usable_travel_mm == measured_at_start_[a].usable_travel_mm) continue;
    const auto unit = homing::axis_unit(settings, a);
    spdlog::info("measurement of {}: usable travel {:.3f} {} from the home position; fitting soft_limit_min {:.3f}, "
                 "soft_limit_max {:.3f}, max_seek_travel {:.3f} {} (not written: homingctl measure {} --apply writes "
                 "them)",
                 homing::kAxisUpper[a], m.usable_travel_mm, unit, m.soft_limit_min_mm, m.soft_limit_max_mm,
                 m.max_seek_travel_mm, unit, homing::kAxisLetters[a]);
  }
}

}  // namespace server
