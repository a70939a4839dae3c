#pragma once
// How homingctl's subcommands are put together: each group of subcommands
// (cmd_*.cpp) declares its options and one function per subcommand; main
// parses, runs the subcommand given and turns errors into exit codes.
#include <CLI/CLI.hpp>

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "actions.hpp"
#include "connection.hpp"

namespace homingctl {

inline constexpr int kOk = 0, kFailed = 1, kUsage = 2, kNoLink = 3;

// A usage error found after parsing (exit 2).
struct Usage : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// The global options, and the module connection opened on first use.
struct Context {
  ConnectionOptions co;
  ActionOptions ao;
  bool json = false;
  // As typed; turned into co and ao by finish_options().
  std::string word_order = "high-first";
  std::string parity = "E";
  bool no_wait = false;
  double timeout_s = 300;
  std::string daemon_config;  // --daemon-config (local_daemon.hpp)
  std::string db = "homingd.db";  // the daemon's database file, for history

  void finish_options();
  Connection& connection();
  // Prints an action's outcome (JSON, or its message on stdout or stderr); its exit code.
  int report(const ActionResult& r) const;

 private:
  std::unique_ptr<Connection> conn_;
};

void print_json(const nlohmann::json& j);

using Run = std::function<int(Context&)>;

// The subcommands as they are declared, each with the function that runs it.
class Commands {
 public:
  explicit Commands(CLI::App& app) : app_(app) {}
  CLI::App* add(const std::string& name, const std::string& help, Run run);
  // The subcommand given on the command line (after parsing), or nullptr.
  const Run* chosen() const;
  // --no-wait and --timeout-s of the commands that move the machine.
  void add_wait_options(CLI::App* sub, Context& ctx);

 private:
  CLI::App& app_;
  std::vector<std::pair<CLI::App*, Run>> commands_;
};

// The groups (cmd_*.cpp), in the order --help lists them.
void add_view_commands(Commands& commands, Context& ctx);      // status, watch
void add_motion_commands(Commands& commands, Context& ctx);    // home, abort, reset, jog, move
void add_settings_commands(Commands& commands, Context& ctx);  // get, set, check, export, import
void add_history_command(Commands& commands, Context& ctx);    // history
void add_trace_command(Commands& commands);                    // trace

}  // namespace homingctl
