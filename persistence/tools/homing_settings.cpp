// homing-settings: the module's settings database from the command line,
// without the module (for a machine that does not start, or a copied file).
//   homing-settings --db /var/lib/homing/homingd.db show
//   homing-settings --db ... export machine-7.toml
//   homing-settings --db ... check
// Opens the database read-only (safe while the module runs). Import is done by
// the module itself, which validates it like Modbus writes. The history (homing
// runs, settings changes, home corrections) has one reader: `homingctl history`.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "persistence/settings_file.hpp"
#include "persistence/settings_store.hpp"
#include "registers/settings_file_values.hpp"

namespace {

constexpr int kFailed = 1, kUsage = 2;

// Where the history subcommands of earlier versions went.
int moved_to_homingctl(std::string_view subcommand, const std::string& db) {
  fmt::print(stderr, "homing-settings {}: the history is read by homingctl: homingctl history --db {} "
                     "(homing runs -n, settings changes --changes, home corrections --corrections)\n",
             subcommand, db);
  return kUsage;
}

int show(const persistence::SettingsStore& store) {
  if (store.settings_lost()) fmt::print("# SETTINGS LOST: running on defaults, not yet acknowledged\n");
  for (const auto& [name, value] : store.load()) fmt::print("{} = {}\n", name, value);
  return 0;
}

// Engineering values and value names (format_version 2), the file homingctl
// export and homingd --export-settings write and every importer reads.
const persistence::SettingsFileCodec kCodec{registers::file_value_text, registers::raw_of_file_value};

int export_to(const persistence::SettingsStore& store, const std::string& file) {
  if (auto s = store.export_file(file, &kCodec); !s) {
    fmt::print(stderr, "error: {}\n", s.error().message);
    return kFailed;
  }
  fmt::print("exported {} settings to {}\n", store.load().size(), file);
  return 0;
}

int check(const persistence::SettingsStore& store, const std::string& db, int schema_version) {
  if (auto s = store.check_integrity(); !s) {
    fmt::print(stderr, "error: {}\n", s.error().message);
    return kFailed;
  }
  fmt::print("{}: ok (schema v{})\n", db, schema_version);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Read the homing module's settings database (the history: homingctl history)"};
  std::string db_path = "homingd.db";  // homingd's own --db default, as homingctl history's
  std::string out_file;
  app.add_option("--db", db_path, "settings database file")->capture_default_str();
  auto* show_cmd = app.add_subcommand("show", "all settings (raw register values)");
  auto* export_cmd = app.add_subcommand("export", "write all settings to a TOML file (engineering values, as homingctl export)");
  export_cmd->add_option("file", out_file, "output file")->required();
  auto* check_cmd = app.add_subcommand("check", "integrity check");
  std::vector<CLI::App*> moved;
  for (const char* name : {"audit", "history", "corrections"})
    moved.push_back(app.add_subcommand(name, "")->allow_extras()->group(""));  // hidden: says where it went
  app.require_subcommand(1);
  CLI11_PARSE(app, argc, argv);
  for (CLI::App* m : moved)
    if (*m) return moved_to_homingctl(m->get_name(), db_path);

  spdlog::set_level(spdlog::level::warn);
  persistence::OpenReport report;
  persistence::StoreOptions options;
  options.read_only = true;
  auto store = persistence::SettingsStore::open(db_path, {}, report, options);
  if (!store) {
    fmt::print(stderr, "error: {}\n", store.error().message);
    return 2;
  }
  if (*show_cmd) return show(*store);
  if (*export_cmd) return export_to(*store, out_file);
  if (*check_cmd) return check(*store, db_path, report.schema_version_found);
  return 0;
}
