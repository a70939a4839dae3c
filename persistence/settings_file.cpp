#include "persistence/settings_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <optional>
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

// Flattens [settings] (quoted dotted keys or nested tables) into name -> value.
std::optional<Error> flatten(const std::string& file, const toml::table& table, const std::string& prefix,
                             SettingsFileEntries& out) {
  for (const auto& [key, node] : table) {
    std::string name = prefix.empty() ? std::string(key.str()) : prefix + "." + std::string(key.str());
    auto line = node.source().begin.line;
    if (const auto* sub = node.as_table()) {
      if (auto e = flatten(file, *sub, name, out)) return e;
      continue;
    }
    const auto* i = node.as_integer();
    if (!i)
      return Error{ErrorKind::invalid, fmt::format("{}:{}: '{}' must be an integer (the raw register value), not a "
                                                   "{}; nothing was imported",
                                                   file, line, name, type_name(node.type()))};
    if (out.contains(name))
      return Error{ErrorKind::invalid, fmt::format("{}:{}: '{}' is given twice; nothing was imported", file, line, name)};
    out[name] = SettingsFileEntry{i->get(), line};
  }
  return std::nullopt;
}

}  // namespace

std::string settings_file_text(const std::map<std::string, std::int64_t>& values, std::string_view source,
                               std::int64_t now_ms) {
  std::string text;
  text += "# Homing module settings: raw register values by register name.\n";
  text += fmt::format("# Exported {} from {}.\n", time_text(now_ms, TimeZone::utc), source);
  text += "# Import checks every value exactly like a Modbus write; a bad file changes nothing.\n";
  text += fmt::format("format = \"{}\"\nformat_version = {}\n\n[settings]\n", kFormat, kFormatVersion);
  for (const auto& [name, value] : values) text += fmt::format("{} = {}\n", quote_key(name), value);
  return text;
}

Result<SettingsFileEntries> read_settings_file(const std::string& file) {
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
  if (auto ver = doc["format_version"]; ver) {
    auto v = ver.value<std::int64_t>();
    if (!v || *v > kFormatVersion)
      return fail(ErrorKind::invalid, fmt::format("{}:{}: format_version must be at most {}; nothing was imported",
                                                  file, ver.node()->source().begin.line, kFormatVersion));
  }
  const toml::table* settings = doc["settings"].as_table();
  if (!settings) return fail(ErrorKind::invalid, fmt::format("{}: no [settings] table; nothing was imported", file));
  SettingsFileEntries entries;
  if (auto e = flatten(file, *settings, "", entries)) return std::unexpected(*e);
  return entries;
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
