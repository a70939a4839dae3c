#pragma once
// The settings file: every setting by register name, as TOML. Written by the
// daemon's export and by homingctl, read by both imports; this is the one
// place that knows its layout.
//
// Two spellings of the values, told apart by `format_version`:
//   1  raw register integers ("axis.x.pull_off" = 2250), the first files;
//   2  engineering values and value names (axis.x.pull_off = 2.25  # mm,
//      axis.x.direction = "negative"), as people read them.
// Persistence knows no units: the register layer passes a SettingsFileCodec
// that spells a raw value for version 2 and reads one back. Version-1 files
// stay readable with or without it.
#include <cstdint>
#include <expected>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <variant>

#include "persistence/error.hpp"

namespace persistence {

inline constexpr std::int64_t kRawFormatVersion = 1;
inline constexpr std::int64_t kEngineeringFormatVersion = 2;

// A value as the file spells it: an integer, a decimal number, true/false or a text.
using SettingsFileValue = std::variant<std::int64_t, double, bool, std::string>;
// The value as it reads in the file ("1500.0", "\"negative\"", "true"), for messages.
std::string file_spelling(const SettingsFileValue& value);

struct SettingsFileEntry {
  SettingsFileValue value;
  std::uint32_t line = 0;  // for messages that point into the file
};
using SettingsFileEntries = std::map<std::string, SettingsFileEntry>;

struct SettingsFile {
  std::int64_t format_version = kRawFormatVersion;  // a file that does not say is version 1
  SettingsFileEntries entries;
};

// How a setting is spelled in a version-2 file (given by the register layer).
struct SettingsFileCodec {
  // A raw value as a TOML value, optionally followed by "  # comment" (the unit).
  // `all`: every value of the file, for a spelling that depends on another
  // setting (the unit of an axis's values on its axis.<a>.kind).
  std::function<std::string(const std::string& name, std::int64_t raw,
                            const std::map<std::string, std::int64_t>& all)>
      write;
  // A file value back to the raw value, or why it cannot be (names the setting,
  // the value and the rule).
  std::function<std::expected<std::int64_t, std::string>(const std::string& name, const SettingsFileValue& value)> read;
};

// The file's text; `source` says where the values came from (a database, a
// module). With a codec: version 2 (engineering values); without: version 1.
std::string settings_file_text(const std::map<std::string, std::int64_t>& values, std::string_view source,
                               std::int64_t now_ms, const SettingsFileCodec* codec = nullptr);

// Parses a settings file (format and version checked, nested tables flattened).
// Names are not judged here: that is the importer's validation.
Result<SettingsFile> read_settings_file(const std::string& file);

// The raw value of every entry: version 1 takes integers as they are, version 2
// reads each value with the codec. Every value that cannot be read is named
// (file:line: name = value: rule), all of them in one error.
Result<std::map<std::string, std::int64_t>> raw_values(const std::string& file, const SettingsFile& parsed,
                                                       const SettingsFileCodec* codec);

// Writes via a temporary file, fsync and rename: never a half-written file.
Status write_file_atomically(const std::string& file, const std::string& text);

}  // namespace persistence
