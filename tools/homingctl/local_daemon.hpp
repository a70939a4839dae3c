#pragma once
// Where the homingd on this computer listens, read from its config file
// (/etc/homingd/homingd.toml as the package installs it, or $HOMINGD_CONFIG,
// or --daemon-config), so that `homingctl status` on the module's computer
// needs no options. What the command line gives always wins.
#include <expected>
#include <optional>
#include <string>

#include "connection.hpp"

namespace homingctl {

inline constexpr const char* kPackagedDaemonConfig = "/etc/homingd/homingd.toml";

struct LocalDaemon {
  std::string path;                // the file these came from
  std::optional<std::string> tcp;  // HOST:PORT to connect to (a wildcard listen address becomes 127.0.0.1)
  std::optional<int> unit;
  std::optional<int> sim_unit;
  std::optional<registers::WordOrder> word_order;
  std::optional<std::string> db;
};

// The config file to read: `explicit_path` if given, else $HOMINGD_CONFIG,
// else the packaged one. named: the user named it (a missing file is an error).
struct DaemonConfigChoice {
  std::string path;
  bool named = false;
};
DaemonConfigChoice choose_daemon_config(const std::string& explicit_path);

// nullopt when the packaged file does not exist (no local daemon installed);
// an error naming the file and the key for a file that cannot be used.
std::expected<std::optional<LocalDaemon>, std::string> read_local_daemon(const DaemonConfigChoice& choice);

// Which connection options the command line gave.
struct GivenOptions {
  bool tcp = false, unit = false, sim_unit = false, word_order = false, db = false;
};

// Fills what the command line left at its default from the daemon's config.
void apply_local_daemon(const LocalDaemon& local, const GivenOptions& given, ConnectionOptions& co, std::string& db);

}  // namespace homingctl
