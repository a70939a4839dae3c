// The generated parts of docs/ must be what the tables generate today, and say
// what a technician reads there for every alarm.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "homing/alarms.hpp"
#include "registers/exports_docs.hpp"
#include "registers/lookup.hpp"
#include "registers/table.hpp"

namespace {

std::string committed(const std::string& name) {
  std::ifstream in(std::string(DOCS_DIR) + "/" + name, std::ios::binary);
  std::stringstream have;
  have << in.rdbuf();
  return in ? have.str() : std::string();
}

std::string alarm_section() {
  for (const auto& s : registers::generate_doc_sections())
    if (s.name == "alarms") return s.content;
  FAIL("no generated alarm section");
  return "";
}

}  // namespace

TEST_CASE("docs/registers.md and the alarm list of docs/troubleshooting.md are fresh") {
  for (const auto& file : registers::generate_doc_files()) {
    INFO("docs/" << file.name << " is stale; regenerate with: " << registers::kDocsCommand);
    CHECK(committed(file.name) == file.content);
  }
  for (const auto& section : registers::generate_doc_sections()) {
    const std::string have = committed(section.file);
    const auto want = registers::splice_section(have, section);
    INFO("docs/" << section.file << ": the generated " << section.name
                 << (want ? " is stale" : " has no marker lines") << "; regenerate with: " << registers::kDocsCommand);
    REQUIRE(want.has_value());
    CHECK(have == *want);
  }
}

TEST_CASE("every register table in the guides of docs/ is what the register table generates today") {
  int tables = 0;
  std::set<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(DOCS_DIR)) {
    if (entry.path().extension() != ".md") continue;
    const std::string name = entry.path().filename().string();
    const std::string have = committed(name);
    const auto found = registers::register_sections(name, have);
    INFO(found.error);
    REQUIRE(found.error.empty());
    const auto want = registers::splice_register_sections(name, have);
    REQUIRE(want.text.has_value());
    INFO("docs/" << name << ": a generated register table is stale; regenerate with: " << registers::kDocsCommand);
    CHECK(have == *want.text);
    tables += static_cast<int>(found.sections.size());
    if (!found.sections.empty()) files.insert(name);
  }
  // The guides whose register tables were typed by hand before.
  for (const char* guide : {"homing-methods.md", "limit-switches.md", "health.md"}) {
    INFO(guide);
    CHECK(files.count(guide) == 1);
  }
  CHECK(tables >= 3);
}

TEST_CASE("a register table naming a register the table lacks is refused with the marker and the name") {
  const std::string marker = "registers axis.<a>.limits_nc axis.<a>.no_such_setting";
  const std::string doc = "# Guide\n\n" + registers::begin_marker(marker) + "\nold\n" + registers::end_marker(marker) + "\n";
  const auto found = registers::register_sections("fixture.md", doc);
  CHECK(found.sections.empty());
  CHECK(found.error.find("docs/fixture.md") != std::string::npos);
  CHECK(found.error.find("'axis.<a>.no_such_setting'") != std::string::npos);
  const auto spliced = registers::splice_register_sections("fixture.md", doc);
  CHECK_FALSE(spliced.text.has_value());
  CHECK(spliced.error == found.error);
}

TEST_CASE("a register table shows each named register's offset, unit, range and default from the table") {
  const std::string marker = "registers axis.<a>.limit_overtravel global.watchdog_ms";
  const std::string doc = registers::begin_marker(marker) + "\n| typed by hand |\n" + registers::end_marker(marker) + "\n";
  const auto spliced = registers::splice_register_sections("fixture.md", doc);
  REQUIRE(spliced.text.has_value());
  CHECK(spliced.text->find("typed by hand") == std::string::npos);
  for (const char* name : {"axis.<a>.limit_overtravel", "global.watchdog_ms"}) {
    const registers::Register* r = nullptr;
    for (const registers::Register& row : registers::all_registers())
      if (row.pattern == name && row.axis <= 0) r = &row;
    REQUIRE(r != nullptr);
    INFO(name);
    const auto at = spliced.text->find("| `" + std::string(name) + "` |");
    REQUIRE(at != std::string::npos);
    const std::string line = spliced.text->substr(at, spliced.text->find('\n', at) - at);
    const std::string address = r->per_axis() ? "+" + std::to_string(r->offset) : std::to_string(r->address);
    CHECK(line.find(" " + address) != std::string::npos);
    CHECK(line.find("| " + std::string(r->unit_text(registers::AxisKinds{})) + " |") != std::string::npos);
    CHECK(line.find("| " + registers::exports_detail::engineering_text(*r, r->default_raw) + " |") != std::string::npos);
    CHECK(line.find(registers::exports_detail::engineering_text(*r, r->max) + " |") != std::string::npos);
  }
}

TEST_CASE("the troubleshooting guide gives every alarm its code, name, text, how to confirm it and what to check") {
  const std::string list = alarm_section();
  for (std::uint8_t c = 1; c < homing::kAlarmCodeCount; ++c) {
    const auto code = static_cast<homing::AlarmCode>(c);
    const auto& info = homing::kAlarmInfo[c];
    INFO("alarm " << int(c) << " " << info.name);
    const auto at = list.find("### " + std::to_string(c) + " `" + std::string(info.name) + "`\n");
    REQUIRE(at != std::string::npos);
    const auto next = list.find("\n### ", at + 1);
    const std::string entry = list.substr(at, next == std::string::npos ? std::string::npos : next - at);
    CHECK(entry.find("**What happened:** " + std::string(info.text)) != std::string::npos);
    CHECK(!registers::alarm_how_to_confirm(code).empty());
    CHECK(entry.find("**How to confirm:** " + std::string(registers::alarm_how_to_confirm(code))) != std::string::npos);
    CHECK(entry.find("**What to check:** " + std::string(homing::alarm_what_to_check(code))) != std::string::npos);
  }
}

TEST_CASE("the register reference gives each setting its unit and default from the table") {
  const std::string md = committed("registers.md");
  int rows = 0;
  for (const registers::Register& r : registers::all_registers()) {
    if (r.table != registers::Table::holding_register || r.axis != 0 || r.unit_text(registers::AxisKinds{}).empty())
      continue;
    INFO(r.pattern);
    const auto at = md.find("| `" + std::string(r.pattern) + "` |");
    REQUIRE(at != std::string::npos);
    const std::string row = md.substr(at, md.find('\n', at) - at);
    const std::string unit(r.unit_text(registers::AxisKinds{}));
    CHECK(row.find("| " + unit + " |") != std::string::npos);
    CHECK(row.find("| " + registers::exports_detail::engineering_text(r, r.default_raw) + " " + unit + " |") !=
          std::string::npos);
    ++rows;
  }
  CHECK(rows > 10);
}

TEST_CASE("a document without the marker lines gets no generated section") {
  const registers::GeneratedSection s{"troubleshooting.md", "alarms", "text\n"};
  CHECK_FALSE(registers::splice_section("# Troubleshooting\nno markers here\n", s).has_value());
  const std::string doc = "intro\n" + registers::begin_marker("alarms") + "\nold list\n" + registers::end_marker("alarms") + "\nafter\n";
  CHECK(registers::splice_section(doc, s) ==
        "intro\n" + registers::begin_marker("alarms") + "\ntext\n\n" + registers::end_marker("alarms") + "\nafter\n");
}
