#include "start_up.hpp"

#include <cstdio>
#include <vector>

#include "registers/defaults.hpp"

namespace server {

int fail_start(const std::string& message) {
  std::fprintf(stderr, "homingd: %s\n", message.c_str());
  return 1;
}

std::expected<std::optional<homing::gpiod::BackendConfig>, std::string> read_wiring(const Options& opt) {
  if (opt.backend != "gpiod") return std::nullopt;
  if (opt.time_scale != 1.0)
    return std::unexpected("--time-scale: simulator only; the GPIO backend runs in real time");
  auto config = homing::gpiod::load_config(opt.config_path);
  if (!config) return std::unexpected("--backend gpiod: " + config.error());
  return std::move(*config);
}

std::expected<persistence::SettingsStore, std::string> open_settings(const Options& opt) {
  std::vector<persistence::SettingDefault> defaults;
  for (const auto& [name, value] : registers::persisted_defaults()) defaults.push_back({name, value});
  persistence::OpenReport report;
  persistence::StoreOptions store_options;
  store_options.backup_on_commit = false;  // the monitor writes backups: no answer waits for one
  auto store = persistence::SettingsStore::open(opt.db_path, defaults, report, store_options);
  if (!store) return std::unexpected("--db " + opt.db_path + ": " + store.error().message);
  return std::move(*store);
}

}  // namespace server
