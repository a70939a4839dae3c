// homingctl: the operator's command-line client of homingd (Modbus TCP, RTU, or
// Modbus/TCP Security with --tls).
// It knows the register table by name and unit. Exit codes: 0 ok, 1 the
// operation failed (alarm, refused command or write: the reason is printed),
// 2 usage error, 3 cannot connect / no answer. The subcommands are in
// cmd_*.cpp, one function each (cli.hpp).
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "cli.hpp"
#include "local_daemon.hpp"

using namespace homingctl;

namespace {

void add_global_options(CLI::App& app, Context& ctx) {
  ConnectionOptions& co = ctx.co;
  app.add_option("--tcp", co.tcp, "Modbus TCP address HOST:PORT (default: the local homingd's, from --daemon-config, else this)")
      ->capture_default_str();
  app.add_option("--daemon-config", ctx.daemon_config,
                 "homingd config file whose tcp, unit, sim_unit, word_order and db are the defaults here "
                 "(default: $HOMINGD_CONFIG, else /etc/homingd/homingd.toml when it exists)");
  app.add_option("--rtu", co.rtu, "Modbus RTU serial device (instead of TCP)");
  app.add_option("--tls", co.tls, "Modbus/TCP Security address HOST[:PORT] (port 802 when not given), instead of TCP");
  app.add_option("--cert", co.cert, "with --tls: this client's certificate (PEM; its role decides what it may do)");
  app.add_option("--key", co.key, "with --tls: the private key of --cert (PEM)");
  app.add_option("--ca", co.ca, "with --tls: the CA certificate that signed the module's certificate (PEM)");
  app.add_option("--baud", co.baud, "RTU baud rate")->capture_default_str();
  app.add_option("--parity", ctx.parity, "RTU parity N|E|O")->check(CLI::IsMember({"N", "E", "O"}))->capture_default_str();
  app.add_option("--stop-bits", co.stop_bits, "RTU stop bits")->check(CLI::IsMember({1, 2}))->capture_default_str();
  app.add_option("--unit", co.unit, "module unit id")->check(CLI::Range(0, 247))->capture_default_str();
  app.add_option("--sim-unit", co.sim_unit, "simulator unit id (0 = none)")->check(CLI::Range(0, 255))->capture_default_str();
  app.add_option("--word-order", ctx.word_order, "word order of 32-bit values (as homingd --word-order)")
      ->check(CLI::IsMember({"high-first", "low-first"}))
      ->capture_default_str();
  app.add_option("--timeout-ms", co.timeout_ms, "response timeout per request")->check(CLI::Range(10, 60000))->capture_default_str();
  app.add_flag("--json", ctx.json, "machine-readable output (read commands)");
}

// The local homingd's config fills what the command line left at its default;
// false when a config file the user named cannot be used (said on stderr).
bool apply_daemon_config(CLI::App& app, Context& ctx) {
  const auto choice = choose_daemon_config(ctx.daemon_config);
  auto local = read_local_daemon(choice);
  if (!local) {
    fmt::print(stderr, "homingctl: {}{}\n", local.error(), choice.named ? "" : " (ignored)");
    return !choice.named;
  }
  if (*local) {
    const GivenOptions given{app.get_option("--tcp")->count() > 0 || !ctx.co.rtu.empty() || !ctx.co.tls.empty(),
                             app.get_option("--unit")->count() > 0, app.get_option("--sim-unit")->count() > 0,
                             app.get_option("--word-order")->count() > 0,
                             app.get_subcommand("history")->get_option("--db")->count() > 0};
    apply_local_daemon(**local, given, ctx.co, ctx.db);
  }
  return true;
}

// Runs the chosen subcommand; what went wrong becomes its exit code and a line on stderr.
int run(const Run& command, Context& ctx) {
  try {
    return command(ctx);
  } catch (const std::invalid_argument& e) {  // Usage, and unknown register names
    fmt::print(stderr, "homingctl: {}\n", e.what());
    return kUsage;
  } catch (const LinkError& e) {
    fmt::print(stderr, "homingctl: {}\n", e.what());
    return kNoLink;
  } catch (const std::exception& e) {  // ModbusException among them
    fmt::print(stderr, "homingctl: {}\n", e.what());
    return kFailed;
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"homingctl: status, commands, settings and traces of the homing module over Modbus.\n"
               "Exit codes: 0 ok, 1 operation failed (reason printed), 2 usage error, 3 cannot connect / no answer."};
  app.fallthrough();
  app.require_subcommand(1);
  Context ctx;
  add_global_options(app, ctx);
  Commands commands(app);
  add_view_commands(commands, ctx);
  add_motion_commands(commands, ctx);
  add_settings_commands(commands, ctx);
  add_history_command(commands, ctx);
  add_trace_command(commands);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    (void)app.exit(e);
    return kUsage;
  }
  ctx.finish_options();
  if (!apply_daemon_config(app, ctx)) return kUsage;
  const Run* command = commands.chosen();
  return command ? run(*command, ctx) : kOk;
}
