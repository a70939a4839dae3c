#include "daemon.hpp"
#include "thread_name.hpp"

#include <pthread.h>
#include <signal.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <expected>
#include <memory>
#include <string>
#include <thread>

#include "control_loop.hpp"
#include "database_lock.hpp"
#include "last_stops.hpp"
#include "homing/gpiod/gpiod_io.hpp"
#include "homing/gpiod/gpiod_lines.hpp"
#include "homing/sim/simulator_io.hpp"
#include "modbus_service.hpp"
#include "monitor.hpp"
#include "mqtt_node.hpp"
#include "plant_events.hpp"
#include "registers/defaults.hpp"
#include "registers/sim_bindings.hpp"
#include "rtu_server.hpp"
#include "start_up.hpp"
#include "systemd_notify.hpp"
#include "tcp_server.hpp"
#include "tls_channel.hpp"

namespace server {
namespace {

using Wiring = std::optional<homing::gpiod::BackendConfig>;

// Signals are taken by the main thread only, with sigwait: every thread
// started after this inherits the mask.
sigset_t take_signals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  signal(SIGPIPE, SIG_IGN);
  return signals;
}

// The stored settings; values the table refuses are logged and replaced by
// defaults. Lines without an axis's step/dir are accepted in the wiring; the
// settings must not ask such an axis to move (checked again on every write).
std::expected<homing::Settings, std::string> load_settings(persistence::SettingsStore& store, const Options& opt,
                                                           const Wiring& wiring) {
  auto from_raw = registers::settings_from_raw(store.load());
  for (const auto& r : from_raw.rejected) spdlog::warn("settings: {}", r);
  if (wiring) {
    if (auto problem = homing::gpiod::check_wiring(*wiring, from_raw.settings))
      return std::unexpected("--backend gpiod: " + opt.config_path + ": the settings in " + opt.db_path +
                             " do not fit the wiring: " + *problem);
  }
  const auto rows = from_raw.settings.global.history_max_rows;
  if (auto r = store.set_limits(rows, rows); !r) spdlog::warn("settings: history limit not applied: {}", r.error().message);
  return from_raw.settings;
}

// The GPIO lines requested, or the simulated machine with the table's
// defaults, its carriages where they were kept (as a real machine's stay).
std::expected<std::unique_ptr<homing::MachineIo>, std::string> open_machine(const Options& opt, const Wiring& wiring,
                                                                           persistence::SettingsStore& store) {
  if (!wiring) {
    homing::sim::MachineConfig config = registers::default_sim_config();
    const persistence::SimCarriages kept = kept_sim_carriages(store);
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (kept[a]) config.axes[a].actual_position_mm = *kept[a];
    return std::make_unique<homing::sim::SimulatorIo>(config);
  }
  homing::gpiod::RunOptions run;
  run.control_period_us = opt.period_us;
  run.warn = [](const std::string& m) { spdlog::warn("{}", m); };
  auto io = homing::gpiod::GpiodIo::open(*wiring, std::make_unique<homing::gpiod::GpiodLines>(), run);
  if (!io) return std::unexpected("--backend gpiod: " + io.error());
  return std::move(*io);
}

ServiceConfig service_config(const Options& opt, const ControlLoop& loop, const Wiring& wiring) {
  ServiceConfig config;
  config.unit_id = static_cast<std::uint8_t>(opt.unit_id);
  config.sim_unit_id = static_cast<std::uint8_t>(opt.sim_unit_id);
  if (!loop.has_sim()) config.sim_unit_id = std::nullopt;  // no simulator behind real GPIO
  config.word_order = opt.word_order;
  for (const auto& entry : opt.write_allow) config.write_allow.push_back(*parse_cidr(entry));
  config.unlock_code = static_cast<std::uint32_t>(opt.unlock_code);
  config.unlock_policy.first_lockout = std::chrono::seconds(opt.unlock_lockout_s);
  config.unlock_policy.max_lockout = std::chrono::seconds(opt.unlock_lockout_max_s);
  config.refusal_log_interval = std::chrono::seconds(opt.refusal_log_interval_s);
  if (!opt.vendor_name.empty()) config.identity.vendor_name = opt.vendor_name;
  if (!opt.vendor_url.empty()) config.identity.vendor_url = opt.vendor_url;
  if (!opt.product_name.empty()) config.identity.product_name = opt.product_name;
  if (!opt.machine_name.empty()) config.identity.user_application_name = opt.machine_name;
  if (wiring) config.machine_check = [w = *wiring](const homing::Settings& s) { return homing::gpiod::check_wiring(w, s); };
  return config;
}

struct Transports {
  std::unique_ptr<TcpServer> tcp;
  std::unique_ptr<TcpServer> tls;  // Modbus/TCP Security
  TlsOpener* tls_files = nullptr;  // tls's opener: reloads its files on SIGHUP
  std::unique_ptr<RtuServer> rtu;
};

// Where a listener listens and how it shares its connections (plain TCP and TLS alike).
ListenConfig listen_config(const Options& opt, const std::string& host, int port) {
  ListenConfig config;
  config.host = host;
  config.port = port;
  config.max_clients = opt.max_clients;
  config.idle_timeout_s = opt.idle_timeout_s;
  config.poll_us = opt.poll_us;
  for (const auto& entry : opt.privileged) config.privileged.push_back(*parse_cidr(entry));
  config.max_per_address = opt.max_clients_per_address;
  config.refusal_log_interval_s = opt.refusal_log_interval_s;
  return config;
}

// The TLS listener: certificate, key, CA and CRL loaded, bound; the error names the file or address.
std::expected<void, std::string> open_tls(const Options& opt, ModbusService& service, Transports& t) {
  auto opener = TlsOpener::create(TlsConfig{{opt.tls_cert, opt.tls_key, opt.tls_ca, opt.tls_crl}, opt.tls_default_role});
  if (!opener) return std::unexpected(opener.error());
  TlsOpener* files = opener->get();
  auto server = std::make_unique<TcpServer>(listen_config(opt, opt.tls_host, opt.tls_port), service, std::move(*opener));
  if (auto r = server->listen(); !r) return std::unexpected(r.error());
  t.tls = std::move(server);
  t.tls_files = files;
  return {};
}

// SIGHUP: the TLS files read again (a new CRL, a renewed certificate); the
// machine keeps running either way.
void reload_tls(const Options& opt, Transports& t) {
  if (!t.tls_files) {
    spdlog::info("SIGHUP received: nothing to reload (no --tls)");
    return;
  }
  if (auto r = t.tls_files->reload(); !r) {
    spdlog::error("SIGHUP received: TLS files not reloaded, the previous ones stay in use: {}", r.error());
    return;
  }
  spdlog::info("SIGHUP received: TLS files reloaded ({}, {}, {}{}); new connections use them", opt.tls_cert,
               opt.tls_key, opt.tls_ca, opt.tls_crl.empty() ? "" : ", " + opt.tls_crl);
}

// Bound and opened, not yet serving; the error names the address or device.
std::expected<Transports, std::string> open_transports(const Options& opt, ModbusService& service) {
  Transports t;
  if (opt.tcp_enabled) {
    t.tcp = std::make_unique<TcpServer>(listen_config(opt, opt.tcp_host, opt.tcp_port), service);
    if (auto r = t.tcp->listen(); !r) return std::unexpected(r.error());
  }
  if (opt.tls_enabled) {
    if (auto r = open_tls(opt, service, t); !r) return std::unexpected(r.error());
  }
  if (!opt.rtu_device.empty()) {
    t.rtu = std::make_unique<RtuServer>(RtuConfig{opt.rtu_device, opt.baud, opt.parity, opt.stop_bits, opt.unit_id,
                                                  std::chrono::milliseconds(opt.rtu_jog_release_ms)},
                                        service);
    if (auto r = t.rtu->open(); !r) return std::unexpected(r.error());
  }
  return t;
}

// The line tests and scripts wait for: homingd is ready. Returns where it listens.
std::string announce(const Options& opt, const Transports& t, bool has_sim) {
  std::string where;
  if (t.tcp) where += "tcp " + opt.tcp_host + ":" + std::to_string(opt.tcp_port);
  if (t.tls)
    where += std::string(where.empty() ? "" : ", ") + "tls " + opt.tls_host + ":" + std::to_string(opt.tls_port);
  if (t.rtu) where += std::string(where.empty() ? "" : ", ") + "rtu " + opt.rtu_device + " " + std::to_string(opt.baud) +
                      " 8" + opt.parity + std::to_string(opt.stop_bits);
  // The simulator unit is served over TCP and TLS only.
  const std::string sim_unit =
      has_sim && (t.tcp || t.tls) ? ", simulator unit " + std::to_string(opt.sim_unit_id) : std::string();
  std::printf("homingd: listening on %s (unit %d%s, backend %s, db %s)\n", where.c_str(), opt.unit_id,
              sim_unit.c_str(), opt.backend.c_str(), opt.db_path.c_str());
  std::fflush(stdout);
  return where;
}

// What the stop did to the axes that moved: where each was, how fast, and
// where it came to rest (a stop at the axis's acceleration travels v²/2a).
void log_stop(const StopReport& r) {
  bool any = false;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const StopReport::Axis& x = r.axes[a];
    if (!x.moving) continue;
    any = true;
    const auto unit = x.unit;
    spdlog::info("stop: {} decelerated from {:.3f} {}/s at {:.3f} {} to rest at {:.3f} {} ({:.3f} {} in {:.3f} s)",
                 homing::kAxisUpper[a], x.velocity_mm_per_s, unit, x.from_mm, unit, x.rest_mm, unit,
                 std::abs(x.rest_mm - x.from_mm), unit, r.machine_s);
  }
  if (!r.at_rest) spdlog::error("stop: axes still moving {:.1f} s after the stop began; leaving anyway", r.machine_s);
  else if (!any) spdlog::info("stop: no axis was moving");
}

// Runs the loop, the monitor and the transports until SIGINT or SIGTERM (a
// SIGHUP reloads the TLS files), then stops them: motion begins to brake at
// once (the loop takes no new motion command from then on, so a client
// served while the transports close cannot start one), the transports close,
// and the loop ends once every axis is at rest.
void serve(const Options& opt, const sigset_t& signals, ControlLoop& loop, ModbusService& service,
           persistence::SettingsStore& store, Transports& t, std::unique_ptr<MqttNode> mqtt, PlantEvents* events) {
  loop.start(opt.rt_priority);
  Monitor monitor(loop, service, &store, [&t]() -> std::uint32_t {
    return static_cast<std::uint32_t>((t.tcp ? t.tcp->active_clients() : 0) + (t.tls ? t.tls->active_clients() : 0));
  });
  monitor.set_plant_events(events);
  monitor.start();
  if (mqtt) mqtt->start();  // Sparkplug B edge node: its own threads, never in the loop's way
  std::thread tcp_thread, tls_thread, rtu_thread;
  if (t.tcp) tcp_thread = std::thread([&] {
    name_this_thread("tcp-accept");
    t.tcp->run();
  });
  if (t.tls) tls_thread = std::thread([&] {
    name_this_thread("tls-accept");
    t.tls->run();
  });
  if (t.rtu) rtu_thread = std::thread([&] {
    name_this_thread("rtu");
    t.rtu->run();
  });
  SystemdNotifier systemd([&loop] { return loop.snapshot().periods; });  // Type=notify, WatchdogSec=
  systemd.ready("listening on " + announce(opt, t, loop.has_sim()));

  int sig = 0;
  while (sigwait(&signals, &sig) == 0 && sig == SIGHUP) reload_tls(opt, t);
  systemd.stopping();
  spdlog::info("{} received: stopping motion and shutting down", sig == SIGINT ? "SIGINT" : "SIGTERM");
  loop.request_stop();
  if (t.tcp) t.tcp->stop();
  if (t.tls) t.tls->stop();
  if (t.rtu) t.rtu->stop();
  if (tcp_thread.joinable()) tcp_thread.join();
  if (tls_thread.joinable()) tls_thread.join();
  if (rtu_thread.joinable()) rtu_thread.join();
  loop.stop();
  log_stop(loop.stop_report());
  // Before anything that may wait on the network: a clean stop's trust is kept
  // even if a stuck broker connection makes systemd kill what follows.
  keep_last_stops(store, loop.stop_report());  // the only place a clean stop is written
  if (mqtt) mqtt->stop();  // after the stop, so the last values are published; then NDEATH
  monitor.stop();
  t.tcp.reset();
  t.tls.reset();
}

}  // namespace

int run_daemon(const Options& opt, const Wiring& wiring) {
  const sigset_t signals = take_signals();
  // An option's file read before the database is touched: a refused start
  // consumes no last stop (the axes' trust) and exits 2 like every option
  // error (the service's RestartPreventExitStatus).
  std::optional<MqttConfig> mqtt_options;
  if (opt.mqtt_enabled) {
    auto config = mqtt_config(opt);
    if (!config) {
      fail_start(config.error());
      return 2;
    }
    mqtt_options = std::move(*config);
  }
  const auto lock = DatabaseLock::take(opt.db_path);
  if (!lock) return fail_start(lock.error());
  auto store = open_settings(opt);
  if (!store) return fail_start(store.error());
  auto settings = load_settings(*store, opt, wiring);
  if (!settings) return fail_start(settings.error());
  auto machine = open_machine(opt, wiring, *store);
  if (!machine) return fail_start(machine.error());

  ControlLoop loop(*settings, std::move(*machine), opt.period_us, opt.time_scale);
  if (store->settings_lost()) {
    loop.raise_settings_lost();
    loop.run_period(0);  // latched in the snapshot before the first client can read it
  }
  ModbusService service(service_config(opt, loop, wiring), loop, &*store, *settings);
  auto transports = open_transports(opt, service);
  if (!transports) return fail_start(transports.error());
  std::optional<persistence::EventOutbox> outbox;
  std::optional<PlantEvents> events;
  std::unique_ptr<MqttNode> mqtt;
  if (mqtt_options) {
    auto config = std::move(mqtt_options);
    auto opened = persistence::EventOutbox::open(config->outbox, config->outbox_max);
    if (!opened) return fail_start("--mqtt-outbox " + config->outbox + ": " + opened.error().message);
    outbox.emplace(std::move(*opened));
    if (const auto owed = outbox->size(); owed > 0)
      spdlog::info("mqtt: {} events from before this start are owed to the broker ({})", owed, outbox->path());
    events.emplace(*outbox, &*store);
    try {
      mqtt = std::make_unique<MqttNode>(std::move(*config), service, &*outbox);
    } catch (const std::runtime_error& e) {
      return fail_start(e.what());
    }
  }

  // Last, once nothing else can refuse the start (a port taken, a TLS file
  // or the outbox that cannot be used): the clean marks are wiped as they are
  // taken, and a start that ended here would have cost every axis its trust.
  // Still before anything can move and before the first client is served.
  if (const auto stops = take_last_stops(*store, *settings)) {
    loop.restore_last_stops(*stops);
    loop.run_period(0);  // trust shown before the first client can read it
  }
  serve(opt, signals, loop, service, *store, *transports, std::move(mqtt), events ? &*events : nullptr);
  store->close();
  spdlog::info("stopped cleanly");
  return 0;
}

}  // namespace server
