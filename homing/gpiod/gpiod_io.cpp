#include "gpiod_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <fmt/format.h>

namespace homing::gpiod {
namespace {

// Beyond this the sum of the loop's periods and the clock disagree for a
// reason other than jitter (a stalled loop): start the timeline again.
constexpr std::int64_t kResyncNs = 50'000'000;

}  // namespace

GpiodIo::GpiodIo(const BackendConfig& config, std::unique_ptr<LineApi> lines, RunOptions options)
    : lines_(std::move(lines)), options_(std::move(options)) {
  dir_setup_ns_ = config.dir_setup_us * 1000;
  tick_ns_ = config.tick_us * 1000;
  input_debounce_ns_ = config.input_debounce_ms * 1'000'000;
  rt_priority_ = config.rt_priority;
  // apply() hands over each period's command right after the engine computed
  // it, so the pulses start where the engine's period starts: no delay is
  // needed (one only shifts the reference by feed x delay).
  playback_delay_ns_ = config.playback_delay_us * 1000;
}

std::expected<std::unique_ptr<GpiodIo>, std::string> GpiodIo::open(const BackendConfig& config,
                                                                   std::unique_ptr<LineApi> lines,
                                                                   RunOptions options) {
  std::unique_ptr<GpiodIo> io(new GpiodIo(config, std::move(lines), std::move(options)));
  if (auto r = io->request_all(config); !r) {
    io->shut_down_ = true;  // nothing was driven yet; the LineApi releases what it took
    return std::unexpected(r.error());
  }
  if (io->options_.start_pulse_thread) {
    std::vector<StepGenerator*> gens;
    for (Axis& a : io->axes_)
      if (a.generator) gens.push_back(a.generator.get());
    io->pulse_thread_ = std::make_unique<PulseThread>(std::move(gens), io->tick_ns_, io->rt_priority_);
    if (auto warning = io->pulse_thread_->start(); !warning.empty()) io->options_.warn(warning);
  }
  return io;
}

std::expected<void, std::string> GpiodIo::request_all(const BackendConfig& c) {
  LineApi& api = *lines_;
  auto output = [&](const std::optional<LineSpec>& spec, OutputLine& out) -> std::expected<void, std::string> {
    if (!spec) return {};
    auto id = api.request_output(*spec, false);  // every output starts inactive: motors disabled
    if (!id) return std::unexpected(id.error());
    out.id = *id;
    return {};
  };
  // A level input is requested with its edges' events too, so that an edge
  // wakes an idle control loop. A line that cannot give events (a GPIO
  // expander without an interrupt) is read as a plain level: it is then seen
  // only in the periods the loop runs, at the latest at its slow tick while idle.
  auto level = [&](const std::optional<LineSpec>& spec, std::int64_t debounce_ns,
                   std::unique_ptr<LevelInput>& out) -> std::expected<void, std::string> {
    if (!spec) return {};
    bool events = true;
    auto id = api.request_input_events(*spec);
    if (!id) {
      events = false;
      id = api.request_input(*spec);
      if (!id) return std::unexpected(id.error());
      options_.warn(fmt::format("gpiod: {}: no edge events on this line; read as a level in each control period, "
                                "so while idle a change shows at the loop's slow tick",
                                describe(*spec)));
    }
    auto v = api.get_value(*id);
    if (!v) return std::unexpected(v.error());
    out = std::make_unique<LevelInput>(api, *id, debounce_ns, *v, events);
    if (events) watch(*id);
    return {};
  };
  auto edges = [&](const std::optional<LineSpec>& spec,
                   std::unique_ptr<EdgeInput>& out) -> std::expected<void, std::string> {
    if (!spec) return {};
    auto id = api.request_input_events(*spec);
    if (!id) return std::unexpected(id.error());
    auto v = api.get_value(*id);
    if (!v) return std::unexpected(v.error());
    out = std::make_unique<EdgeInput>(api, *id, *v);
    watch(*id);
    return {};
  };
  for (std::size_t i = 0; i < kAxisCount; ++i) {
    const AxisLines& cfg = c.axes[i];
    Axis& a = axes_[i];
    if (!cfg.configured) continue;
    a.configured = true;
    OutputLine step, dir;
    for (auto r : {output(cfg.step, step), output(cfg.dir, dir), output(cfg.enable, a.enable),
                   output(cfg.push, a.push), output(cfg.commutator, a.commutator), edges(cfg.home, a.home),
                   edges(cfg.index, a.index), level(cfg.drive_fault, 0, a.drive_fault), level(cfg.stall, 0, a.stall),
                   output(cfg.home_request, a.home_request), level(cfg.home_done, input_debounce_ns_, a.home_done),
                   output(cfg.unlock, a.unlock), level(cfg.unlocked, 0, a.unlocked),
                   level(cfg.limit_min, 0, a.limit_min), level(cfg.limit_max, 0, a.limit_max)})
      if (!r) return r;
    if (step.id && dir.id)  // an axis without an output of its own has no pulses to make
      a.generator = std::make_unique<StepGenerator>(api, *step.id, *dir.id, cfg.steps_per_unit, dir_setup_ns_);
  }
  // Safety inputs act at once; the operator's inputs are debounced.
  for (auto r : {level(c.estop, 0, estop_), level(c.drive_fault, 0, drive_fault_),
                 level(c.start_button, input_debounce_ns_, start_button_),
                 level(c.homing_permit, input_debounce_ns_, homing_permit_), output(c.homing_done_lamp, lamp_)})
    if (!r) return r;
  return {};
}

GpiodIo::~GpiodIo() { shutdown(); }

void GpiodIo::watch(LineId line) {
  if (const int fd = lines_->event_fd(line); fd >= 0) event_fds_.push_back(fd);
}

double GpiodIo::quiet_for_s(const Outputs& outputs) const {
  (void)outputs;  // the engine is quiet: they move nothing
  if (shut_down_) return 0;
  double quiet_s = std::numeric_limits<double>::infinity();
  auto settling = [&](const std::unique_ptr<LevelInput>& in) {
    // A debounced change counts at its time: the loop must run a period then.
    if (in && in->settling())
      quiet_s = std::min(quiet_s, static_cast<double>(in->settles_at_ns() - period_end_ns_) * 1e-9);
  };
  for (const Axis& a : axes_) {
    if (!a.configured) continue;
    // Edges after the end of the last period: the next period takes them.
    if ((a.home && a.home->has_pending()) || (a.index && a.index->has_pending())) return 0;
    for (const auto* in : {&a.drive_fault, &a.stall, &a.home_done, &a.unlocked, &a.limit_min, &a.limit_max})
      settling(*in);
  }
  for (const auto* in : {&estop_, &drive_fault_, &start_button_, &homing_permit_}) settling(*in);
  return std::max(quiet_s, 0.0);
}

void GpiodIo::write(OutputLine& out, bool value) {
  if (!out.id || out.value == value) return;
  if (auto r = lines_->set_value(*out.id, value); !r) {
    input_failed(r.error());
    return;
  }
  out.value = value;
}

void GpiodIo::input_failed(const std::string& message) {
  input_fault_ = true;
  if (message != last_input_error_) options_.warn("gpiod: " + message + "; e-stop raised until it recovers");
  last_input_error_ = message;
}

void GpiodIo::advance(const Outputs& outputs, double dt_s) {
  if (shut_down_) return;
  const std::int64_t now = options_.clocks.monotonic_ns();
  const std::int64_t dt_ns = std::llround(std::max(dt_s, 0.0) * 1e9);
  // The loop's periods add up to its own clock; follow their sum (several
  // short periods may be run at once when the loop is late).
  if (!anchored_ || std::llabs(period_end_ns_ + dt_ns - now) > kResyncNs) {
    period_end_ns_ = now - dt_ns;
    anchored_ = dt_ns > 0;
  }
  period_start_ns_ = period_end_ns_;
  period_end_ns_ += dt_ns;
  (void)outputs;  // already running since apply()
}

void GpiodIo::apply(const Outputs& outputs) {
  if (shut_down_) return;
  // The engine's motor state is that of the instant its period began: the end
  // of the period just read. The previous segment runs on until this one starts.
  const std::int64_t start = period_end_ns_ + playback_delay_ns_;
  for (std::size_t i = 0; i < kAxisCount; ++i) {
    Axis& a = axes_[i];
    if (!a.configured) continue;
    const AxisOutputs& o = outputs.axes[i];
    if (a.generator) a.generator->push(Segment{start, o.motor, o.motion});
    write(a.enable, o.enable);
    write(a.push, o.push_output);
    write(a.commutator, o.commutator_output);
    write(a.home_request, o.drive_request);
    write(a.unlock, o.indexer_unlock);
  }
  write(lamp_, outputs.homing_done_lamp);
  if (pulse_thread_) pulse_thread_->wake();  // asleep while every generator rested
}

Inputs GpiodIo::read() {
  Inputs in{};
  if (shut_down_) {
    in.estop = true;
    return in;
  }
  input_fault_ = false;
  const std::int64_t mono = options_.clocks.monotonic_ns();
  const std::int64_t real = options_.clocks.realtime_ns();
  const std::int64_t end = period_end_ns_;
  auto sample = [&](const std::unique_ptr<LevelInput>& line) {
    if (!line) return false;
    auto v = line->sample(end);
    if (v) return *v;
    input_failed(v.error());
    return false;
  };
  for (std::size_t i = 0; i < kAxisCount; ++i) {
    Axis& a = axes_[i];
    if (!a.configured) continue;
    AxisInputs& ai = in.axes[i];
    for (auto [input, edges, level, rising_only] :
         {std::tuple{a.home.get(), &ai.sensor_edges, &ai.sensor_level, false},
          std::tuple{a.index.get(), &ai.index_edges, &ai.index_level, true}}) {
      if (!input) continue;
      if (auto r = input->poll(mono, real); !r) input_failed(r.error());
      input->take(period_start_ns_, end, rising_only, *edges, *level);
    }
    ai.drive_fault = sample(a.drive_fault);
    ai.stall = sample(a.stall);
    ai.drive_done = sample(a.home_done);
    ai.indexer_unlocked = sample(a.unlocked);
    ai.limit_min_level = sample(a.limit_min);
    ai.limit_max_level = sample(a.limit_max);
    if (a.generator && a.generator->failed()) {
      // A step or dir write failed: the motor no longer follows the count.
      ai.drive_fault = true;
      if (a.reported_failure.empty()) {
        a.reported_failure = a.generator->failure();
        options_.warn("gpiod: " + a.reported_failure + "; the axis reports a drive fault");
      }
    }
  }
  const bool global_fault = sample(drive_fault_);
  for (std::size_t i = 0; i < kAxisCount; ++i)
    if (axes_[i].configured) in.axes[i].drive_fault = in.axes[i].drive_fault || global_fault;
  in.estop = sample(estop_);
  in.start_button = sample(start_button_);
  in.homing_permit = sample(homing_permit_);
  // An input that cannot be read might be the e-stop: stop everything.
  if (input_fault_) in.estop = true;
  return in;
}

void GpiodIo::shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  if (pulse_thread_) pulse_thread_->stop();
  for (Axis& a : axes_) {
    if (!a.configured) continue;
    if (a.generator) a.generator->idle();
    write(a.enable, false);
    write(a.push, false);
    write(a.commutator, false);
    write(a.home_request, false);
    write(a.unlock, false);  // the indexer locks: nothing drives the axis any more
  }
  write(lamp_, false);
}

}  // namespace homing::gpiod
