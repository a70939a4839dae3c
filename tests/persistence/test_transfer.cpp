#include <catch2/catch.hpp>

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "helpers.hpp"
#include "persistence/settings_file.hpp"

using namespace persistence;

namespace {

std::string read_all(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Like the register layer: the X seek feedrate must be 1..20000, and Y mode
// may only be 5 when X mode is 5 too (a cross-register rule).
std::optional<Rejection> validator(const std::map<std::string, std::int64_t>& all) {
  auto feed = all.at("axis.x.seek_feedrate");
  if (feed < 1 || feed > 20000) return Rejection{"axis.x.seek_feedrate", "must be 1..20000 mm/min"};
  if (all.at("axis.y.mode") == 5 && all.at("axis.x.mode") != 5) return Rejection{"", "Y mode 5 needs X mode 5"};
  return std::nullopt;
}

}  // namespace

TEST_CASE("an export is a readable file with every setting by name", "[persistence][transfer]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  REQUIRE(store.export_file(dir.file("machine.toml")));
  auto text = read_all(dir.file("machine.toml"));
  CHECK_THAT(text, Catch::Contains("\"axis.x.home_position\" = -1500"));
  CHECK_THAT(text, Catch::Contains("[settings]"));
  CHECK_THAT(text, Catch::Contains("# Homing module settings"));
}

TEST_CASE("an exported file clones the settings onto another machine", "[persistence][transfer]") {
  test::TempDir dir;
  OpenReport report;
  auto a = test::open_ok(dir.file("a.db"), report);
  REQUIRE(a.commit({{"axis.x.mode", 5}, {"axis.x.home_position", 250}, {"global.watchdog_ms", 100}}, test::kTcp));
  REQUIRE(a.export_file(dir.file("machine.toml")));
  auto b = test::open_ok(dir.file("b.db"), report);
  auto r = b.import_file(dir.file("machine.toml"), validator);
  REQUIRE(r);
  CHECK(r->changes.size() == 3);
  CHECK(r->not_in_file.empty());
  CHECK(b.load() == a.load());
  auto audit = b.recent_changes(10);
  REQUIRE(audit);
  CHECK(audit->size() == 3);
  CHECK(audit->front().transport == "import");
  CHECK(audit->front().client == dir.file("machine.toml"));
  b.close();
  CHECK(test::open_ok(dir.file("b.db"), report).value("axis.x.home_position") == 250);
}

TEST_CASE("a hand-written file may use nested tables and leave registers out", "[persistence][transfer]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  test::write_text(dir.file("partial.toml"), "[settings.axis.x]\nmode = 6\nseek_feedrate = 1800\n");
  auto r = store.import_file(dir.file("partial.toml"), validator);
  REQUIRE(r);
  CHECK(store.value("axis.x.mode") == 6);
  CHECK(store.value("axis.x.seek_feedrate") == 1800);
  CHECK(r->not_in_file.size() == 3);
}

TEST_CASE("a file with a value the register rules reject changes nothing and names the line", "[persistence][transfer]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  test::write_text(dir.file("bad.toml"),
                   "[settings]\n\"axis.x.mode\" = 4\n\"axis.x.seek_feedrate\" = 99999\n");
  auto r = store.import_file(dir.file("bad.toml"), validator);
  REQUIRE_FALSE(r);
  CHECK(r.error().kind == ErrorKind::invalid);
  CHECK_THAT(r.error().message, Catch::Contains(dir.file("bad.toml") + ":3:") &&
                                    Catch::Contains("axis.x.seek_feedrate") && Catch::Contains("1..20000"));
  CHECK(store.value("axis.x.mode") == 3);
  CHECK(store.recent_changes(10)->empty());
}

TEST_CASE("a file breaking a cross-register rule changes nothing", "[persistence][transfer]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  test::write_text(dir.file("bad.toml"), "[settings]\n\"axis.y.mode\" = 5\n");
  auto r = store.import_file(dir.file("bad.toml"), validator);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("Y mode 5 needs X mode 5"));
  CHECK(store.value("axis.y.mode") == 0);
}

TEST_CASE("an unknown register, a wrong type or broken syntax in the file is reported with its line",
          "[persistence][transfer]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  const auto f = dir.file("bad.toml");

  test::write_text(f, "[settings]\n\"axis.x.mode\" = 4\n\"axis.w.mode\" = 1\n");
  auto r = store.import_file(f, validator);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains(f + ":3:") && Catch::Contains("unknown register 'axis.w.mode'"));

  test::write_text(f, "[settings]\n\"axis.x.mode\" = \"four\"\n");
  r = store.import_file(f, validator);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains(f + ":2:") && Catch::Contains("must be an integer"));

  test::write_text(f, "[settings]\n\"axis.x.mode\" = 4\n\"axis.y.mode\" = \n");
  r = store.import_file(f, validator);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains(f + ":3:") && Catch::Contains("not valid TOML"));

  r = store.import_file(dir.file("missing.toml"), validator);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("missing.toml"));

  test::write_text(f, "format = \"something-else\"\n[settings]\n");
  r = store.import_file(f, validator);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains(f + ":1:"));

  CHECK(store.value("axis.x.mode") == 3);
  CHECK(store.recent_changes(10)->empty());
}

namespace {

// Like the register layer's codec: "mm" settings are written and read in mm
// (raw µm / 1000), everything else as the raw integer; a text is refused.
const SettingsFileCodec kMmCodec{
    [](const std::string& name, std::int64_t raw, const std::map<std::string, std::int64_t>&) {
      return name.ends_with("position") ? fmt::format("{:.3f}  # mm", raw / 1000.0) : std::to_string(raw);
    },
    [](const std::string& name, const SettingsFileValue& v) -> std::expected<std::int64_t, std::string> {
      if (const auto* d = std::get_if<double>(&v)) return std::llround(*d * 1000);
      if (const auto* i = std::get_if<std::int64_t>(&v)) return name.ends_with("position") ? *i * 1000 : *i;
      return std::unexpected(fmt::format("{} = {}: not a number", name, file_spelling(v)));
    }};

}  // namespace

TEST_CASE("with the register layer's codec the file holds engineering values and reads back exactly",
          "[persistence][transfer]") {
  test::TempDir dir;
  OpenReport report;
  auto a = test::open_ok(dir.file("a.db"), report);
  REQUIRE(a.commit({{"axis.x.home_position", -12500}, {"axis.x.mode", 5}}, test::kTcp));
  REQUIRE(a.export_file(dir.file("machine.toml"), &kMmCodec));
  const auto text = read_all(dir.file("machine.toml"));
  CHECK_THAT(text, Catch::Contains("format_version = 2\n"));
  CHECK_THAT(text, Catch::Contains("\naxis.x.home_position = -12.500  # mm\n"));
  CHECK_THAT(text, Catch::Contains("\naxis.x.mode = 5\n"));

  auto b = test::open_ok(dir.file("b.db"), report);
  auto r = b.import_file(dir.file("machine.toml"), validator, &kMmCodec);
  REQUIRE(r);
  CHECK(b.load() == a.load());

  // Without the codec an engineering file is not guessed at: refused, nothing changed.
  auto c = test::open_ok(dir.file("c.db"), report);
  r = c.import_file(dir.file("machine.toml"), validator);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("format_version 2") && Catch::Contains("nothing was imported"));
  CHECK(c.value("axis.x.home_position") == test::open_ok(dir.file("d.db"), report).value("axis.x.home_position"));
}

TEST_CASE("every value of an engineering file that cannot be read is named with its line, and nothing changes",
          "[persistence][transfer]") {
  test::TempDir dir;
  OpenReport report;
  auto store = test::open_ok(dir.file("settings.db"), report);
  const auto before = store.load();
  test::write_text(dir.file("bad.toml"), "format_version = 2\n[settings]\naxis.x.home_position = 2.5\n"
                                         "axis.x.mode = \"fast\"\naxis.y.mode = \"slow\"\n");
  auto r = store.import_file(dir.file("bad.toml"), validator, &kMmCodec);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("2 values cannot be imported") &&
                                    Catch::Contains(dir.file("bad.toml") + ":4: axis.x.mode = \"fast\": not a number") &&
                                    Catch::Contains(dir.file("bad.toml") + ":5: axis.y.mode = \"slow\": not a number"));
  CHECK(store.load() == before);

  // A raw file does not accept decimals, and says how to write engineering values.
  test::write_text(dir.file("raw.toml"), "format_version = 1\n[settings]\n\"axis.x.home_position\" = 2.5\n");
  r = store.import_file(dir.file("raw.toml"), validator, &kMmCodec);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains(":3: 'axis.x.home_position' must be an integer") &&
                                    Catch::Contains("format_version = 2"));
  test::write_text(dir.file("future.toml"), "format_version = 3\n[settings]\n");
  r = store.import_file(dir.file("future.toml"), validator, &kMmCodec);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("format_version must be 1 (raw register values) or 2"));
  // Not an integer (found by fuzz_settings_import: 1e44 was converted out of range, undefined behaviour).
  for (const char* version : {"2.0", "1e44", "-1e44", "\"2\""}) {
    INFO(version);
    test::write_text(dir.file("odd.toml"), std::string("format_version = ") + version + "\n[settings]\n");
    r = store.import_file(dir.file("odd.toml"), validator, &kMmCodec);
    REQUIRE_FALSE(r);
    CHECK_THAT(r.error().message, Catch::Contains(":1: format_version must be 1 (raw register values) or 2"));
  }
  CHECK(store.load() == before);
}
