#include "settings_file_mode.hpp"

#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "persistence/settings_file.hpp"
#include "registers/settings_file_values.hpp"
#include "registers/validate.hpp"
#include "database_lock.hpp"
#include "start_up.hpp"

namespace server {
namespace {

// Engineering values and value names (format_version 2), as homingctl writes them.
const persistence::SettingsFileCodec kCodec{registers::file_value_text, registers::raw_of_file_value};

int export_settings(const persistence::SettingsStore& store, const Options& opt) {
  if (auto r = store.export_file(opt.export_settings, &kCodec); !r) return fail_start("--export-settings: " + r.error().message);
  std::printf("homingd: settings of %s written to %s\n", opt.db_path.c_str(), opt.export_settings.c_str());
  return 0;
}

// Validated exactly like Modbus writes: a file the module would refuse changes nothing.
int import_settings(persistence::SettingsStore& store, const Options& opt) {
  auto validate = [](const std::map<std::string, std::int64_t>& all) -> std::optional<persistence::Rejection> {
    if (auto refusal = registers::validate_settings_map(all)) return persistence::Rejection{"", refusal->message};
    return std::nullopt;
  };
  auto r = store.import_file(opt.import_settings, validate, &kCodec);
  if (!r) return fail_start("--import-settings " + opt.import_settings + ": " + r.error().message + "; nothing changed");
  std::printf("homingd: %zu settings changed from %s\n", r->changes.size(), opt.import_settings.c_str());
  for (const auto& c : r->changes)
    std::printf("  %s: %lld -> %lld\n", c.name.c_str(), static_cast<long long>(c.old_value),
                static_cast<long long>(c.new_value));
  return 0;
}

}  // namespace

bool is_settings_file_mode(const Options& opt) { return !opt.export_settings.empty() || !opt.import_settings.empty(); }

int run_settings_file_mode(const Options& opt) {
  // An export is a backup: of a database that is not there it would write
  // factory defaults (and create the database), a backup of nothing.
  if (!opt.export_settings.empty() && !std::filesystem::exists(opt.db_path))
    return fail_start("--export-settings: no settings database at " + opt.db_path +
                      " (check --db, or the service's db in /etc/homingd/homingd.toml); nothing was written");
  // Not beside a running daemon: an import would change settings under it.
  const auto lock = DatabaseLock::take(opt.db_path);
  if (!lock)
    return fail_start(lock.error() + (opt.export_settings.empty()
                                          ? "; while it runs, homingctl import FILE changes its settings over Modbus"
                                          : "; while it runs, homingctl export FILE or homing-settings --db " +
                                                opt.db_path + " export FILE write the same file"));
  auto store = open_settings(opt);
  if (!store) return fail_start(store.error());
  if (!opt.export_settings.empty()) {
    if (store->settings_lost())
      return fail_start("--export-settings: the settings of " + opt.db_path +
                        " were lost (damaged, no usable backup): the file would hold factory defaults; nothing was "
                        "written (see docs/troubleshooting.md, settings_lost)");
    return export_settings(*store, opt);
  }
  return import_settings(*store, opt);
}

}  // namespace server
