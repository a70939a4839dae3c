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

// For the troubleshooting guide: how a technician confirms what an alarm says
// ("" for none and for a code without a line).
std::string_view alarm_how_to_confirm(homing::AlarmCode code);

inline constexpr std::string_view kDocsCommand = "build/bin/gen_hmi_maps --out hmi_maps --docs docs";

}  // namespace registers
