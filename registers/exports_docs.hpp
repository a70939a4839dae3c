#pragma once
// The generated parts of docs/: the register reference (docs/registers.md, a
// whole file) and the alarm list of docs/troubleshooting.md (a section between
// two marker lines in a hand-written file). Both come from the same tables as
// hmi_maps/ (registers/table.cpp, homing/alarms.hpp); gen_hmi_maps --docs DIR
// writes them and a test compares them with the committed files.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "homing/alarms.hpp"
#include "registers/exports.hpp"

namespace registers {

// A part of a hand-written document between the line begin_marker(name) and
// the line end_marker(name).
struct GeneratedSection {
  std::string file;  // inside docs/
  std::string name;
  std::string content;
};

std::vector<GeneratedFile> generate_doc_files();
std::vector<GeneratedSection> generate_doc_sections();

std::string begin_marker(std::string_view name);
std::string end_marker(std::string_view name);
// The document with the section's lines replaced by its content; nothing when
// the document lacks either marker line.
std::optional<std::string> splice_section(const std::string& document, const GeneratedSection& section);

// A table of registers in any document of docs/, between the lines
//   begin_marker("registers NAME NAME ...") and end_marker("registers NAME NAME ...")
// where each NAME is a register as the reference spells it (axis.<a>.limits_nc,
// sim.<a>.limit_min, global.watchdog_ms): one row per name, in that order, with
// its address (per-axis rows: table and offset in the axis block), type, unit,
// range, default and description from the register table. error names the
// marker and what is wrong with it (a name the table lacks, a repeated marker,
// a begin line without its end line); then sections is empty.
struct RegisterSections {
  std::vector<GeneratedSection> sections;
  std::string error;
};
RegisterSections register_sections(std::string_view file, const std::string& document);
// The document with every register section in it regenerated; nothing (and
// the error) as register_sections.
struct SplicedDocument {
  std::optional<std::string> text;
  std::string error;
};
SplicedDocument splice_register_sections(std::string_view file, const std::string& document);

// For the troubleshooting guide: how a technician confirms what an alarm says
// ("" for none and for a code without a line).
std::string_view alarm_how_to_confirm(homing::AlarmCode code);

inline constexpr std::string_view kDocsCommand = "build/bin/gen_hmi_maps --out hmi_maps --docs docs";

}  // namespace registers
