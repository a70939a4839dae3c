// libFuzzer target: `homingd --import-settings FILE`. The input is written as
// a settings TOML file and imported into a temporary database with
// persistence::SettingsStore::import_file, the register layer's codec for
// engineering values and registers::validate_settings_map as the validator,
// as server/settings_file_mode.cpp does. Besides "no crash": a refused import
// leaves load() exactly as before; an accepted one leaves only values the
// daemon accepts at start (settings_from_raw rejects none), and exactly the
// file's values: each setting the file names as the file says, every other
// one as before (the file read again here, apart from the import). After an accepted import the previous values are committed
// back, so every input starts from the defaults. The database is opened once
// and reused (on tmpfs when there is one); its settings at the start of every
// input are the defaults read once at start, which each input's checks
// restore and prove.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

#include "fuzz_common.hpp"
#include "persistence/settings_file.hpp"
#include "persistence/settings_store.hpp"
#include "registers/defaults.hpp"
#include "registers/settings_file_values.hpp"
#include "registers/validate.hpp"

namespace {

struct Fixture {
  std::filesystem::path dir;
  std::string file;
  std::unique_ptr<persistence::SettingsStore> store;
  std::map<std::string, std::int64_t> defaults;  // load() at start: every input starts and ends with it
};

Fixture& fixture() {
  static Fixture f = [] {
    Fixture x;
    x.dir = fuzz::scratch_dir() / ("homing-fuzz-import-" + std::to_string(::getpid()));
    std::filesystem::remove_all(x.dir);
    std::filesystem::create_directories(x.dir);
    x.file = (x.dir / "settings.toml").string();
    std::vector<persistence::SettingDefault> defaults;
    for (const auto& [name, value] : registers::persisted_defaults()) defaults.push_back({name, value});
    persistence::OpenReport report;
    persistence::StoreOptions options;
    options.backup_min_interval = std::chrono::hours(1);  // backups are not what is fuzzed here
    auto store = persistence::SettingsStore::open((x.dir / "settings.db").string(), defaults, report, options);
    if (!store) {
      std::fprintf(stderr, "cannot open the fuzz database: %s\n", store.error().message.c_str());
      std::abort();
    }
    x.store = std::make_unique<persistence::SettingsStore>(std::move(*store));
    x.defaults = x.store->load();
    return x;
  }();
  return f;
}

// Engineering values (format_version 2) read as homingd reads them.
const persistence::SettingsFileCodec kCodec{registers::file_value_text, registers::raw_of_file_value};

std::optional<persistence::Rejection> validate(const std::map<std::string, std::int64_t>& all) {
  if (auto refusal = registers::validate_settings_map(all)) return persistence::Rejection{"", refusal->message};
  return std::nullopt;
}

void check(bool ok, const char* what) {
  if (!ok) fuzz::violated(what, 0, {});
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet_logs();
  fuzz::remove_stale_temp_files("homing-fuzz-import-");
  (void)fixture();  // constructed before the handler is registered: destroyed after it ran
  std::atexit([] {
    fixture().store.reset();
    std::error_code ec;
    std::filesystem::remove_all(fixture().dir, ec);
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Fixture& f = fixture();
  {
    std::ofstream out(f.file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  const auto& before = f.defaults;  // what the previous input restored and checked
  const auto imported = f.store->import_file(f.file, validate, &kCodec);
  const auto after = f.store->load();
  if (!imported) {
    check(!imported.error().message.empty(), "a refused import without a message");
    check(after == before, "a refused import changed the settings");
    return 0;
  }
  const auto from_raw = registers::settings_from_raw(after);
  check(from_raw.rejected.empty(), "an accepted import stored a value the daemon rejects at start");
  // What is stored is what the file says, read here on its own: every setting
  // it names has the file's value, every other one kept its value.
  const auto parsed = persistence::read_settings_file(f.file);
  check(parsed.has_value(), "an accepted import of a file that does not parse");
  const auto in_file = persistence::raw_values(f.file, *parsed, &kCodec);
  check(in_file.has_value(), "an accepted import of a value that does not read");
  auto expected = before;
  for (const auto& [name, value] : *in_file) expected[name] = value;
  check(after == expected, "an accepted import stored other values than the file's, or changed a setting it does not name");
  for (const auto& c : imported->changes) {
    auto it = after.find(c.name);
    check(it != after.end() && it->second == c.new_value, "a reported change is not what is stored");
  }
  // Back to the previous values for the next input.
  std::vector<persistence::SettingWrite> restore;
  for (const auto& [name, value] : before) restore.push_back({name, value});
  check(f.store->commit(restore, persistence::ChangeSource{"fuzz", "restore"}).has_value(), "restore failed");
  check(f.store->load() == before, "restore did not restore");
  return 0;
}
