// homingd: the homing module's daemon. Modbus TCP and RTU in front, the
// control loop and the machine (simulator or GPIO) behind, settings in SQLite.
#include <pthread.h>
#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <memory>
#include <thread>

#include "control_loop.hpp"
#include "homing/gpiod/gpiod_io.hpp"
#include "homing/gpiod/gpiod_lines.hpp"
#include "modbus_service.hpp"
#include "monitor.hpp"
#include "options.hpp"
#include "persistence/settings_store.hpp"
#include "registers/defaults.hpp"
#include "registers/sim_bindings.hpp"
#include "registers/validate.hpp"
#include "rtu_server.hpp"
#include "simulator_io.hpp"
#include "systemd_notify.hpp"
#include "tcp_server.hpp"

namespace {

int fail_start(const std::string& message) {
  std::fprintf(stderr, "homingd: %s\n", message.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  auto parsed = server::parse_options(argc, argv);
  if (!parsed) {
    std::fprintf(stderr, "homingd: %s\nRun 'homingd --help' for the options and their accepted values.\n",
                 parsed.error().c_str());
    return 2;
  }
  if (parsed->exit_now) return parsed->exit_code;
  const server::Options& opt = parsed->options;

  auto logger = spdlog::stderr_color_mt("homingd");
  spdlog::set_default_logger(logger);
  spdlog::set_level(spdlog::level::from_str(opt.log_level));
  spdlog::set_pattern("%Y-%m-%d %H:%M:%S.%e %^%l%$ %v");

  // Signals are taken by the main thread only, with sigwait: every thread
  // started below inherits this mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  signal(SIGPIPE, SIG_IGN);

  // The machine's wiring: GPIO lines named in the config file's [gpiod]
  // table, read first so that a mistake in it is reported before anything
  // else starts. The lines are requested once the settings are known.
  std::optional<homing::gpiod::BackendConfig> wiring;
  if (opt.backend == "gpiod") {
    if (opt.time_scale != 1.0) return fail_start("--time-scale: simulator only; the GPIO backend runs in real time");
    auto config = homing::gpiod::load_config(opt.config_path);
    if (!config) return fail_start("--backend gpiod: " + config.error());
    wiring = std::move(*config);
  }

  // Settings: durable, from the register table's defaults on first start.
  std::vector<persistence::SettingDefault> defaults;
  for (const auto& [name, value] : registers::persisted_defaults()) defaults.push_back({name, value});
  persistence::OpenReport report;
  persistence::StoreOptions store_options;
  store_options.backup_on_commit = false;  // the monitor writes backups: no answer waits for one
  auto store = persistence::SettingsStore::open(opt.db_path, defaults, report, store_options);
  if (!store) return fail_start("--db " + opt.db_path + ": " + store.error().message);
  if (!opt.export_settings.empty()) {
    if (auto r = store->export_file(opt.export_settings); !r) return fail_start("--export-settings: " + r.error().message);
    std::printf("homingd: settings of %s written to %s\n", opt.db_path.c_str(), opt.export_settings.c_str());
    return 0;
  }
  if (!opt.import_settings.empty()) {
    auto validate = [](const std::map<std::string, std::int64_t>& all) -> std::optional<persistence::Rejection> {
      if (auto refusal = registers::validate_settings_map(all)) return persistence::Rejection{"", refusal->message};
      return std::nullopt;
    };
    auto r = store->import_file(opt.import_settings, validate);
    if (!r) return fail_start("--import-settings " + opt.import_settings + ": " + r.error().message + "; nothing changed");
    std::printf("homingd: %zu settings changed from %s\n", r->changes.size(), opt.import_settings.c_str());
    for (const auto& c : r->changes)
      std::printf("  %s: %lld -> %lld\n", c.name.c_str(), static_cast<long long>(c.old_value),
                  static_cast<long long>(c.new_value));
    return 0;
  }
  auto from_raw = registers::settings_from_raw(store->load());
  for (const auto& r : from_raw.rejected) spdlog::warn("settings: {}", r);
  // Lines without an axis's step/dir are accepted in the config; the settings
  // must not ask such an axis to move (checked again on every settings write).
  if (wiring) {
    if (auto problem = homing::gpiod::check_wiring(*wiring, from_raw.settings))
      return fail_start("--backend gpiod: " + opt.config_path + ": the settings in " + opt.db_path +
                        " do not fit the wiring: " + *problem);
  }
  const auto rows = from_raw.settings.global.history_max_rows;
  if (auto r = store->set_limits(rows, rows); !r) spdlog::warn("settings: history limit not applied: {}", r.error().message);

  std::unique_ptr<server::MachineIo> machine;
  homing::sim::Simulator* sim = nullptr;
  if (wiring) {
    homing::gpiod::RunOptions run;
    run.control_period_us = opt.period_us;
    run.warn = [](const std::string& m) { spdlog::warn("{}", m); };
    auto io = homing::gpiod::GpiodIo::open(*wiring, std::make_unique<homing::gpiod::GpiodLines>(), run);
    if (!io) return fail_start("--backend gpiod: " + io.error());
    machine = std::move(*io);
  } else {
    auto sim_io = std::make_unique<server::SimulatorIo>(registers::default_sim_config());
    sim = &sim_io->sim();
    machine = std::move(sim_io);
  }
  server::ControlLoop loop(from_raw.settings, std::move(machine), sim, opt.period_us, opt.time_scale);
  if (store->settings_lost()) loop.raise_settings_lost();

  server::ServiceConfig service_config;
  service_config.unit_id = static_cast<std::uint8_t>(opt.unit_id);
  service_config.sim_unit_id = static_cast<std::uint8_t>(opt.sim_unit_id);
  if (!sim) service_config.sim_unit_id = std::nullopt;  // no simulator behind real GPIO
  service_config.word_order = opt.word_order;
  for (const auto& entry : opt.write_allow) service_config.write_allow.push_back(*server::parse_cidr(entry));
  service_config.unlock_code = static_cast<std::uint16_t>(opt.unlock_code);
  if (wiring)
    service_config.machine_check = [w = *wiring](const homing::Settings& s) { return homing::gpiod::check_wiring(w, s); };
  server::ModbusService service(service_config, loop, &*store, from_raw.settings);

  std::unique_ptr<server::TcpServer> tcp;
  if (opt.tcp_enabled) {
    tcp = std::make_unique<server::TcpServer>(opt.tcp_host, opt.tcp_port, opt.max_clients, opt.idle_timeout_s, service);
    if (auto r = tcp->listen(); !r) return fail_start(r.error());
  }
  std::unique_ptr<server::RtuServer> rtu;
  if (!opt.rtu_device.empty()) {
    rtu = std::make_unique<server::RtuServer>(
        server::RtuConfig{opt.rtu_device, opt.baud, opt.parity, opt.stop_bits, opt.unit_id}, service);
    if (auto r = rtu->open(); !r) return fail_start(r.error());
  }

  loop.start(opt.rt_priority);
  server::Monitor monitor(loop, service, &*store, [&tcp]() -> std::uint32_t {
    return tcp ? static_cast<std::uint32_t>(tcp->active_clients()) : 0;
  });
  monitor.start();
  std::thread tcp_thread, rtu_thread;
  if (tcp) tcp_thread = std::thread([&] { tcp->run(); });
  if (rtu) rtu_thread = std::thread([&] { rtu->run(); });

  std::string where;
  if (tcp) where += "tcp " + opt.tcp_host + ":" + std::to_string(opt.tcp_port);
  if (rtu) where += std::string(where.empty() ? "" : ", ") + "rtu " + opt.rtu_device + " " + std::to_string(opt.baud) +
                    " 8" + opt.parity + std::to_string(opt.stop_bits);
  const std::string sim_unit = sim ? ", simulator unit " + std::to_string(opt.sim_unit_id) : std::string();
  std::printf("homingd: listening on %s (unit %d%s, backend %s, db %s)\n", where.c_str(), opt.unit_id,
              sim_unit.c_str(), opt.backend.c_str(), opt.db_path.c_str());
  std::fflush(stdout);
  server::SystemdNotifier systemd([&loop] { return loop.snapshot().periods; });  // Type=notify, WatchdogSec=
  systemd.ready("listening on " + where);

  int sig = 0;
  sigwait(&signals, &sig);
  systemd.stopping();
  spdlog::info("{} received: stopping motion and shutting down", sig == SIGINT ? "SIGINT" : "SIGTERM");
  if (tcp) tcp->stop();
  if (rtu) rtu->stop();
  if (tcp_thread.joinable()) tcp_thread.join();
  if (rtu_thread.joinable()) rtu_thread.join();
  loop.stop();
  monitor.stop();
  tcp.reset();
  store->close();
  spdlog::info("stopped cleanly");
  return 0;
}
