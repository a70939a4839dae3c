#pragma once
// The settings file: every setting by register name, raw values, as TOML.
// Written by the daemon's export and by homingctl, read by both imports; this
// is the one place that knows its layout.
#include <cstdint>
#include <map>
#include <string>
#include <string_view>

#include "persistence/error.hpp"

namespace persistence {

struct SettingsFileEntry {
  std::int64_t value = 0;
  std::uint32_t line = 0;  // for messages that point into the file
};
using SettingsFileEntries = std::map<std::string, SettingsFileEntry>;

// The file's text; `source` says where the values came from (a database, a module).
std::string settings_file_text(const std::map<std::string, std::int64_t>& values, std::string_view source,
                               std::int64_t now_ms);

// Parses a settings file (format and version checked, nested tables flattened).
// Names and values are not judged here: that is the importer's validation.
Result<SettingsFileEntries> read_settings_file(const std::string& file);

// Writes via a temporary file, fsync and rename: never a half-written file.
Status write_file_atomically(const std::string& file, const std::string& text);

}  // namespace persistence
