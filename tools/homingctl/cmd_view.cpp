// status and watch: what the machine is doing, once or live.
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <thread>

#include "cli.hpp"
#include "homing/gantry.hpp"
#include "registers/codec.hpp"
#include "registers/lookup.hpp"
#include "settings_io.hpp"
#include "status_view.hpp"

namespace homingctl {

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

struct WatchOptions {
  int interval_ms = 0;
  double timeout_s = 0;
};

int status(Context& ctx) {
  Connection& c = ctx.connection();
  const auto settings = read_settings(c);
  const auto s = read_status(c, settings);
  if (ctx.json) print_json(status_json(s, settings)); else fmt::print("{}", render_status(s, settings, true));
  return kOk;
}

// The end of the homing cycle that watch saw: 0 homed, 1 with the alarms.
int cycle_ended(const Context& ctx, const StatusView& s, const homing::Settings& settings) {
  std::vector<std::string> alarms;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a)
    if (s.axes[a].alarm != homing::AlarmCode::none) alarms.push_back(alarm_text(a, s.axes[a], settings));
  if (s.state == homing::MachineState::homed && alarms.empty()) {
    if (!ctx.json) fmt::print("homing cycle ended: homed\n");
    return kOk;
  }
  if (!ctx.json) fmt::print(stderr, "homing cycle ended: {}{}{}\n", homing::state_name(s.state),
                            alarms.empty() ? "" : "\n  ", fmt::join(alarms, "\n  "));
  return kFailed;
}

int watch(Context& ctx, const WatchOptions& o) {
  Connection& c = ctx.connection();
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const int period = o.interval_ms > 0 ? o.interval_ms : (ctx.co.rtu.empty() ? 250 : 1000);
  const bool tty = ::isatty(STDOUT_FILENO) && !ctx.json;
  auto settings = read_settings(c);
  const auto start = std::chrono::steady_clock::now();
  bool seen_cycle = false;
  std::string last_frame;
  for (;;) {
    const auto s = read_status(c, settings);
    if (s.homing && !seen_cycle) {
      seen_cycle = true;
      settings = read_settings(c);  // cannot change during the cycle
    }
    const bool ended = seen_cycle && !s.homing && s.state != homing::MachineState::homing;
    if (ctx.json) {
      auto j = status_json(s, settings);
      j["cycle_ended"] = ended;
      fmt::print("{}\n", j.dump());
    } else {
      std::string frame = render_status(s, settings, true);
      if (tty) fmt::print("\033[H\033[2J{}", frame);
      else if (frame != last_frame) fmt::print("{}\n", frame);
      last_frame = frame;
    }
    std::fflush(stdout);
    if (ended) return cycle_ended(ctx, s, settings);
    if (g_stop) return kOk;
    if (o.timeout_s > 0 && std::chrono::steady_clock::now() - start > std::chrono::duration<double>(o.timeout_s))
      return seen_cycle ? kFailed : kOk;
    std::this_thread::sleep_for(std::chrono::milliseconds(period));
  }
}

// The switch figures of the last cycle of each homing axis (docs/health.md),
// read from their registers, with the warnings they raise.
int health(Context& ctx) {
  Connection& c = ctx.connection();
  const auto settings = read_settings(c);
  nlohmann::json j = nlohmann::json::object();
  if (!ctx.json)
    fmt::print("{:<4} {:>6} {:>10} {:>10} {:>10} {:>7} {:>10} {:>10} {:>10}  {}\n", "axis", "passes", "spread", "sigma",
               "hysteresis", "chatter", "seek-latch", "index", "skew", "warnings");
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const homing::AxisSettings& s = settings.axes[a];
    if (!homing::mode_homes(s.mode)) continue;
    const std::string_view letter = homing::kAxisLetters[a];
    auto value = [&](std::string_view suffix) {
      const registers::Register* r = registers::find_register(fmt::format("axis.{}.{}", letter, suffix));
      return registers::to_engineering(*r, c.read(*r));
    };
    const auto u = homing::axis_unit(settings, a);
    const double passes = value("latch_passes_done"), spread = value("latch_spread"), sigma = value("latch_sigma");
    const double hysteresis = value("hysteresis"), seek_latch = value("seek_latch_difference");
    const double chatter = value("chatter_edges"), index = value("index_distance");
    const bool near = value("index_near_edge") != 0;
    const bool slave = homing::gantry_master(settings, a) >= 0;
    const double skew = value("gantry_skew");
    const auto trend = static_cast<homing::HealthWarning>(value("health_warning"));
    std::vector<std::string> warnings;
    if (near)
      warnings.push_back(fmt::format("index pulse {:.3f} {} from the switch edge (index_pitch {:g} {}): switch noise can "
                                     "home one pitch off; move the cam or the encoder's index by about half a pitch",
                                     index, u, s.index_pitch_mm, u));
    // The history's trend (the index warning is said above already); its
    // figures are in the daemon's log and in homingctl history --trend.
    if (trend != homing::HealthWarning::none && trend != homing::HealthWarning::index_near_edge)
      warnings.push_back(fmt::format("{}: {} (homingctl history --trend {})", homing::name_of(trend),
                                     homing::text_of(trend), letter));
    if (ctx.json) {
      j[std::string(letter)] = {{"latch_passes", passes}, {"latch_spread", spread}, {"latch_sigma", sigma},
                                {"hysteresis", hysteresis}, {"chatter_edges", chatter},
                                {"seek_latch_difference", seek_latch}, {"index_distance", index},
                                {"gantry_skew", slave ? nlohmann::json(skew) : nlohmann::json(nullptr)},
                                {"health_warning", std::string(homing::name_of(trend))},
                                {"unit", std::string(u)}, {"warnings", warnings}};
      continue;
    }
    fmt::print("{:<4} {:>6g} {:>10.4f} {:>10.4f} {:>10.4f} {:>7g} {:>10.4f} {:>10.4f} {:>10}  {}\n", homing::kAxisUpper[a],
               passes, spread, sigma, hysteresis, chatter, seek_latch, index,
               slave ? fmt::format("{:.4f}", skew) : "-",
               warnings.empty() ? "-" : fmt::format("{}", fmt::join(warnings, "; ")));
  }
  if (ctx.json) print_json(j);
  else fmt::print("figures of the last homing cycle, in each axis's unit (docs/health.md)\n");
  return kOk;
}

}  // namespace

void add_view_commands(Commands& commands, Context&) {
  commands.add("status", "one table: every axis (mode, phase, position, homed, sensor, alarm), "
                         "the machine state and what blocks motion", status);
  commands.add("health", "switch health per axis from the last homing cycle: latch passes, spread, sigma, "
                         "hysteresis, chatter, seek-latch difference, index distance, a gantry slave's skew, with "
                         "their warnings and the history's trend warning", health);
  auto o = std::make_shared<WatchOptions>();
  auto* sub = commands.add("watch", "status refreshed live with progress bars during homing; exits when a "
                                    "homing cycle ends (0 homed, 1 alarm)",
                           [o](Context& ctx) { return watch(ctx, *o); });
  sub->add_option("--interval-ms", o->interval_ms, "refresh period (default 250 ms on TCP, 1000 ms on RTU)");
  sub->add_option("--timeout-s", o->timeout_s, "stop after this long (0 = until the cycle ends or Ctrl-C)");
}

}  // namespace homingctl
