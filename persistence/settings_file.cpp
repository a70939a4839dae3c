#include "persistence/settings_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <optional>
#include <vector>
#include <cctype>
#include <toml++/toml.h>

#include "persistence/durable_files.hpp"
#include "persistence/time_text.hpp"

namespace persistence {
namespace {

constexpr std::string_view kFormat = "homing-module-settings";
constexpr std::int64_t kFormatVersion = 1;

std::string quote_key(std::string_view k) {
  std::string out = "\"";
  for (char c : k) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  out += '"';
  return out;
}

// Register names are dotted bare keys ("axis.x.mode"); anything else is quoted.
std::string bare_or_quoted_key(std::string_view k) {
  bool bare = !k.empty() && k.front() != '.' && k.back() != '.' && k.find("..") == std::string_view::npos;
  for (char c : k)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) bare = false;
  return bare ? std::string(k) : quote_key(k);
}

std::string_view type_name(toml::node_type t) {
  switch (t) {
    case toml::node_type::string: return "string";
    case toml::node_type::floating_point: return "decimal number";
    case toml::node_type::boolean: return "boolean";
    case toml::node_type::array: return "array";
    case toml::node_type::date:
    case toml::node_type::time:
    case toml::node_type::date_time: return "date/time";
    default: return "value of another kind";
  }
}

std::string_view type_name(const SettingsFileValue& v) {
  switch (v.index()) {
    case 0: return "integer";
    case 1: return "decimal number";
    case 2: return "boolean";
    default: return "string";
  }
}

std::optional<SettingsFileValue> value_of(const toml::node& node) {
  if (const auto* i = node.as_integer()) return SettingsFileValue{i->get()};
  if (const auto* d = node.as_floating_point()) return SettingsFileValue{d->get()};
  if (const auto* b = node.as_boolean()) return SettingsFileValue{b->get()};
  if (const auto* s = node.as_string()) return SettingsFileValue{s->get()};
  return std::nullopt;
}

// Flattens [settings] (dotted keys, quoted dotted keys or nested tables) into name -> value.
std::optional<Error> flatten(const std::string& file, const toml::table& table, const std::string& prefix,
                             SettingsFileEntries& out) {
  for (const auto& [key, node] : table) {
    std::string name = prefix.empty() ? std::string(key.str()) : prefix + "." + std::string(key.str());
    auto line = node.source().begin.line;
    if (const auto* sub = node.as_table()) {
      if (auto e = flatten(file, *sub, name, out)) return e;
      continue;
    }
    auto value = value_of(node);
    if (!value)
      return Error{ErrorKind::invalid, fmt::format("{}:{}: '{}' must be a number, true/false or a text, not a {}; "
                                                   "nothing was imported",
                                                   file, line, name, type_name(node.type()))};
    if (out.contains(name))
      return Error{ErrorKind::invalid, fmt::format("{}:{}: '{}' is given twice; nothing was imported", file, line, name)};
    out[name] = SettingsFileEntry{std::move(*value), line};
  }
  return std::nullopt;
}

std::string header(std::string_view source, std::int64_t now_ms, bool engineering) {
  std::string text;
  if (engineering) {
    text += "# Homing module settings by register name, in engineering units (the unit after '#';\n";
    text += "# deg instead of mm on the rotary axes A B C) and value names, as homingctl get shows them.\n";
  } else {
    text += "# Homing module settings: raw register values by register name.\n";
  }
  text += fmt::format("# Exported {} from {}.\n", time_text(now_ms, TimeZone::utc), source);
  text += "# Import checks every value exactly like a Modbus write; a bad file changes nothing.\n";
  text += fmt::format("format = \"{}\"\nformat_version = {}\n\n[settings]\n", kFormat,
                      engineering ? kEngineeringFormatVersion : kRawFormatVersion);
  return text;
}

// One error for all the values that cannot be read.
Error unreadable(const std::string& file, const std::vector<std::string>& problems) {
  if (problems.size() == 1) return Error{ErrorKind::invalid, problems.front() + "; nothing was imported"};
  std::string message = fmt::format("{}: {} values cannot be imported; nothing was imported:", file, problems.size());
  for (const auto& p : problems) message += "\n  " + p;
  return Error{ErrorKind::invalid, std::move(message)};
}

}  // namespace

std::string file_spelling(const SettingsFileValue& value) {
  switch (value.index()) {
    case 0: return fmt::format("{}", std::get<std::int64_t>(value));
    case 1: {
      std::string s = fmt::format("{}", std::get<double>(value));
      if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // a decimal number reads as one
      return s;
    }
    case 2: return std::get<bool>(value) ? "true" : "false";
    default: return quote_key(std::get<std::string>(value));
  }
}

std::string settings_file_text(const std::map<std::string, std::int64_t>& values, std::string_view source,
                               std::int64_t now_ms, const SettingsFileCodec* codec) {
  std::string text = header(source, now_ms, codec != nullptr);
  for (const auto& [name, value] : values) {
    if (codec) text += fmt::format("{} = {}\n", bare_or_quoted_key(name), codec->write(name, value, values));
    else text += fmt::format("{} = {}\n", quote_key(name), value);
  }
  return text;
}

Result<SettingsFile> read_settings_file(const std::string& file) {
  toml::table doc;
  try {
    doc = toml::parse_file(file);
  } catch (const toml::parse_error& e) {
    const auto& src = e.source();
    if (src.begin.line == 0)
      return fail(ErrorKind::invalid, fmt::format("{}: cannot read the file: {}; nothing was imported", file,
                                                  e.description()));
    return fail(ErrorKind::invalid, fmt::format("{}:{}:{}: not valid TOML: {}; nothing was imported", file,
                                                src.begin.line, src.begin.column, e.description()));
  }
  if (auto fmt_node = doc["format"]; fmt_node) {
    auto v = fmt_node.value<std::string>();
    if (!v || *v != kFormat)
      return fail(ErrorKind::invalid, fmt::format("{}:{}: 'format' must be \"{}\"; nothing was imported", file,
                                                  fmt_node.node()->source().begin.line, kFormat));
  }
  SettingsFile parsed;
  if (auto ver = doc["format_version"]; ver) {
    // An integer node only: toml++'s value<int64_t>() of a float such as 1e44
    // would convert it out of range (undefined behaviour, found by fuzzing).
    const toml::value<std::int64_t>* version = ver.as_integer();
    const std::optional<std::int64_t> v = version ? std::optional(version->get()) : std::nullopt;
    if (!v || *v < kRawFormatVersion || *v > kEngineeringFormatVersion)
      return fail(ErrorKind::invalid,
                  fmt::format("{}:{}: format_version must be {} (raw register values) or {} (engineering values); "
                              "nothing was imported",
                              file, ver.node()->source().begin.line, kRawFormatVersion, kEngineeringFormatVersion));
    parsed.format_version = *v;
  }
  const toml::table* settings = doc["settings"].as_table();
  if (!settings) return fail(ErrorKind::invalid, fmt::format("{}: no [settings] table; nothing was imported", file));
  if (auto e = flatten(file, *settings, "", parsed.entries)) return std::unexpected(*e);
  return parsed;
}

Result<std::map<std::string, std::int64_t>> raw_values(const std::string& file, const SettingsFile& parsed,
                                                       const SettingsFileCodec* codec) {
  const bool engineering = parsed.format_version == kEngineeringFormatVersion;
  if (engineering && !codec)
    return fail(ErrorKind::invalid, fmt::format("{}: a format_version {} file (engineering values) needs the register "
                                                "table to be read: import it with homingd --import-settings or "
                                                "homingctl import; nothing was imported",
                                                file, kEngineeringFormatVersion));
  std::map<std::string, std::int64_t> out;
  std::vector<std::string> problems;
  for (const auto& [name, e] : parsed.entries) {
    if (engineering) {
      auto raw = codec->read(name, e.value);
      if (raw) out[name] = *raw;
      else problems.push_back(fmt::format("{}:{}: {}", file, e.line, raw.error()));
    } else if (const auto* raw = std::get_if<std::int64_t>(&e.value)) {
      out[name] = *raw;
    } else {
      problems.push_back(fmt::format("{}:{}: '{}' must be an integer (the raw register value), not a {} (a file of "
                                     "engineering values and value names says format_version = {})",
                                     file, e.line, name, type_name(e.value), kEngineeringFormatVersion));
    }
  }
  if (!problems.empty()) return std::unexpected(unreadable(file, problems));
  return out;
}

Status write_file_atomically(const std::string& file, const std::string& text) {
  const std::string tmp = file + ".tmp";
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return std::unexpected(os_error(tmp, "creating the file", errno));
  std::size_t done = 0;
  while (done < text.size()) {
    ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      int err = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      return std::unexpected(os_error(tmp, "writing the file", err));
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    int err = errno;
    ::close(fd);
    ::unlink(tmp.c_str());
    return std::unexpected(os_error(tmp, "fsync", err));
  }
  ::close(fd);
  if (::rename(tmp.c_str(), file.c_str()) != 0) {
    int err = errno;
    ::unlink(tmp.c_str());
    return std::unexpected(os_error(file, "renaming the file into place", err));
  }
  return {};
}

}  // namespace persistence
