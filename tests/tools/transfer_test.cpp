// homingctl export/import write and read the same file as persistence's
// export_file/import_file (with the register layer's codec, as homingd uses
// them): a file from one imports into the other. The values are in
// engineering units with value names; raw files of format_version 1 still
// import. Import is checked like a Modbus write and is all or nothing.
#include <catch2/catch.hpp>

#include <fmt/format.h>

#include <fstream>

#include "homing/settings_check.hpp"
#include "persistence/settings_file.hpp"
#include "persistence/settings_store.hpp"
#include "registers/defaults.hpp"
#include "registers/settings_file_values.hpp"
#include "settings_io.hpp"
#include "tools_helpers.hpp"

using namespace tools_test;

namespace {

std::vector<persistence::SettingDefault> defaults() {
  std::vector<persistence::SettingDefault> out;
  for (const auto& [name, value] : registers::persisted_defaults()) out.push_back({name, value});
  return out;
}

// The register layer's rules for a whole settings set (what homingd uses).
std::optional<persistence::Rejection> validate(const std::map<std::string, std::int64_t>& values) {
  const auto s = registers::settings_from_raw(values).settings;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    if (s.axes[a].mode == homing::HomingMode::disabled) continue;
    if (auto f = homing::check_axis(s, a))
      return persistence::Rejection{fmt::format("axis.{}.{}", homing::kAxisLetters[a], homing::field_name(f->field)),
                                    homing::describe_fault(*f, s)};
  }
  return std::nullopt;
}

// homingd's reading of engineering values.
const persistence::SettingsFileCodec kCodec{registers::file_value_text, registers::raw_of_file_value};

// Replaces the value of `name` in an exported file (a line "name = value  # unit").
void replace_value(const std::string& file, const std::string& name, const std::string& value) {
  std::string text = read_file(file);
  const std::string key = "\n" + name + " = ";
  const auto at = text.find(key);
  REQUIRE(at != std::string::npos);
  const auto end = text.find('\n', at + 1);
  text.replace(at, end - at, key + value);
  std::ofstream(file) << text;
}

// The file without its comment header (time and source differ between exports).
std::string from_format(const std::string& text) { return text.substr(text.find("format =")); }

}  // namespace

TEST_CASE("homingctl export imports with persistence's import_file, and persistence's export imports with homingctl") {
  Daemon d;
  TempDir dir;
  Client c = Client::tcp(d.port());
  REQUIRE(ctl(d, {"set", "axis.x.pull_off=2.25", "axis.z.mode=switch_index", "axis.y.home_position=-12.5",
                  "sequence.step3=a", "axis.a.mode=manual"}).code() == 0);
  const std::string exported = dir.file("machine.toml");
  auto r = ctl(d, {"export", exported});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
  }
  const std::string text = read_file(exported);
  CHECK(text.find("format = \"homing-module-settings\"") != std::string::npos);
  CHECK(text.find("\naxis.x.pull_off = 2.25  # mm\n") != std::string::npos);

  // Into a store, read as homingd reads it: every value arrives.
  persistence::OpenReport report;
  auto store = persistence::SettingsStore::open(dir.file("other.db"), defaults(), report);
  REQUIRE(store);
  auto imported = store->import_file(exported, validate, &kCodec);
  REQUIRE(imported);
  CHECK(imported->not_in_file.empty());
  const auto values = store->load();
  CHECK(values.at("axis.x.pull_off") == 2250);
  CHECK(values.at("axis.z.mode") == 4);
  CHECK(values.at("axis.y.home_position") == -12500);
  CHECK(values.at("sequence.step3") == 8);

  // The other way: change the store, export it (raw values, as the first
  // files were), import it with homingctl.
  auto committed = store->commit({{"axis.x.pull_off", 3000}, {"axis.y.seek_feedrate", 1500}, {"axis.a.mode", 0}},
                                 persistence::ChangeSource{"cli", "test"});
  REQUIRE(committed);
  const std::string from_store = dir.file("from-store.toml");
  REQUIRE(store->export_file(from_store));
  r = ctl(d, {"import", from_store});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
    CHECK(r.out.find("changed 3 settings") != std::string::npos);
  }
  CHECK(c.read("axis.x.pull_off") == 3000);
  CHECK(c.read("axis.y.seek_feedrate") == 1500);
  CHECK(c.read("axis.a.mode") == 0);
  // And the module's settings are now exactly the store's.
  const auto module = homingctl::settings_file_text(store->load(), "x", 0);
  auto again = ctl(d, {"export", dir.file("again.toml")});
  REQUIRE(again.code() == 0);
  CHECK(from_format(read_file(dir.file("again.toml"))) == from_format(module));
  // And homingd's own export of the store is the same file.
  REQUIRE(store->export_file(dir.file("store-v2.toml"), &kCodec));
  CHECK(from_format(read_file(dir.file("store-v2.toml"))) == from_format(module));
}

TEST_CASE("homingctl import is checked like a Modbus write, ordered, and all or nothing") {
  Daemon d;
  TempDir dir;
  Client c = Client::tcp(d.port());
  const std::string file = dir.file("machine.toml");
  REQUIRE(ctl(d, {"export", file}).code() == 0);
  const auto before = holding_snapshot(c);

  // A stop distance beyond its limit: refused with the reason, nothing written.
  replace_value(file, "axis.x.pull_off", "4.0");
  replace_value(file, "axis.x.seek_feedrate", "20000.0");
  auto r = ctl(d, {"import", file});
  {
    SHOW(r);
    CHECK(r.code() == 1);
    CHECK(r.err.find("max_stop_distance") != std::string::npos);
  }
  CHECK(holding_snapshot(c) == before);

  // Valid together, but only in one order (max_stop_distance first): imported.
  replace_value(file, "axis.x.seek_feedrate", "12000.0");
  replace_value(file, "axis.x.max_stop_distance", "50.0");
  replace_value(file, "axis.x.max_backoff", "60.0");  // the back-off must release after a 40 mm stop
  r = ctl(d, {"import", "--dry-run", file});
  CHECK(r.code() == 0);
  CHECK(holding_snapshot(c) == before);
  r = ctl(d, {"import", file});
  {
    SHOW(r);
    REQUIRE(r.code() == 0);
  }
  CHECK(c.read("axis.x.seek_feedrate") == 12000);
  CHECK(c.read("axis.x.max_stop_distance") == 50000);
  CHECK(c.read("axis.x.pull_off") == 4000);

  // Bad files name the line.
  std::ofstream(dir.file("bad.toml")) << "format = \"homing-module-settings\"\n[settings]\n\"axis.x.nonsense\" = 3\n";
  r = ctl(d, {"import", dir.file("bad.toml")});
  CHECK(r.code() == 1);
  CHECK(r.err.find("bad.toml:3: unknown register 'axis.x.nonsense'") != std::string::npos);
  std::ofstream(dir.file("float.toml")) << "[settings]\n\"axis.x.pull_off\" = 1.5\n";
  r = ctl(d, {"import", dir.file("float.toml")});
  CHECK(r.code() == 1);
  CHECK(r.err.find("must be an integer") != std::string::npos);
}
