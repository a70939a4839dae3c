#include "config_file.hpp"

#include <charconv>
#include <cmath>
#include <iterator>
#include <toml++/toml.h>

namespace server {
namespace {

// One TOML value as the text CLI11 parses for an option. A kind no option
// takes (a table, an array of arrays, a date or a time, nan, inf) is an error
// naming the key.
std::string option_text(const toml::node& node, const std::string& key) {
  if (const auto* s = node.as_string()) return s->get();
  if (const auto* i = node.as_integer()) return std::to_string(i->get());
  if (const auto* b = node.as_boolean()) return b->get() ? "true" : "false";
  if (const auto* f = node.as_floating_point()) {
    if (!std::isfinite(f->get())) throw ConfigFileError("key '" + key + "': expected a finite number");
    char text[32];
    const auto end = std::to_chars(std::begin(text), std::end(text), f->get()).ptr;
    return std::string(text, end);
  }
  throw ConfigFileError("key '" + key + "': expected a string, a number, true/false or an array of them");
}

}  // namespace

bool ConfigFileReader::is_option_key(const std::string& key) const {
  if (key == "config" || key == "help" || key == "version") return false;
  for (const CLI::Option* opt : app_.get_options())
    for (const auto& name : opt->get_lnames())
      if (name == key) return true;
  return false;
}

std::vector<CLI::ConfigItem> ConfigFileReader::from_config(std::istream& in) const {
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  toml::table file;
  try {
    file = toml::parse(text);
  } catch (const toml::parse_error& e) {
    throw ConfigFileError("line " + std::to_string(e.source().begin.line) + ": " + std::string(e.description()));
  }
  std::vector<CLI::ConfigItem> items;
  for (const auto& [name, value] : file) {
    const std::string key(name.str());
    if (key == "gpiod" && value.is_table()) continue;
    // One-shot actions, not how the service runs: in /etc/homingd/homingd.toml
    // they would end every start with exit 0 (never restarted) and apply a file
    // over the settings written since.
    if (key == "import_settings" || key == "export_settings" || key == "import-settings" || key == "export-settings")
      throw ConfigFileError("key '" + key + "' is a one-shot action, not a setting of the service: give --" +
                            (key.starts_with("import") ? "import" : "export") +
                            "-settings on the command line (homingd --db ... --" +
                            (key.starts_with("import") ? "import" : "export") + "-settings FILE)");
    if (!is_option_key(key) && value.is_table())
      throw ConfigFileError("unknown section [" + key + "] (known: [gpiod])");
    if (!is_option_key(key))
      throw ConfigFileError("unknown key '" + key + "'; keys are the long option names without the leading "
                            "dashes, e.g. tcp = \"0.0.0.0:502\", log_level = \"warn\"");
    CLI::ConfigItem item;
    item.name = key;
    if (const auto* list = value.as_array()) {
      for (const auto& element : *list) item.inputs.push_back(option_text(element, key));
    } else {
      item.inputs.push_back(option_text(value, key));
    }
    items.push_back(std::move(item));
  }
  return items;
}

}  // namespace server
