#pragma once
// homingd's config file (--config FILE): TOML read by toml++, handed to CLI11
// as the values of the long options it names. toml++ reads the whole TOML
// grammar and says on which line a file is wrong; CLI11's own reader would
// ignore a key it does not know, so that a typo fell back to a default.
#include <CLI/CLI.hpp>

#include <istream>
#include <string>
#include <vector>

namespace server {

// What is wrong with the file itself (syntax, unknown key, a value of a kind
// no option takes); OptionParser names the file in front of it.
class ConfigFileError : public CLI::ConfigError {
 public:
  explicit ConfigFileError(std::string msg) : CLI::ConfigError(std::move(msg)) {}
};

class ConfigFileReader final : public CLI::Config {
 public:
  // app: the options a key may name (its long names, without the dashes).
  explicit ConfigFileReader(const CLI::App& app) : app_(app) {}

  // The [gpiod] table is not an option: the GPIO backend reads it
  // (homing/gpiod/config.hpp), so it is left out here.
  std::vector<CLI::ConfigItem> from_config(std::istream& in) const override;

  // CLI11's TOML writer (homingd does not write config files; this keeps
  // App::config_to_str working).
  std::string to_config(const CLI::App* app, bool default_also, bool write_description,
                        std::string prefix) const override {
    return CLI::ConfigTOML().to_config(app, default_also, write_description, std::move(prefix));
  }

 private:
  bool is_option_key(const std::string& key) const;

  const CLI::App& app_;
};

}  // namespace server
