// homingctl: the operator's command-line client of homingd (Modbus TCP or RTU).
// It knows the register table by name and unit. Exit codes: 0 ok, 1 the
// operation failed (alarm, refused command or write: the reason is printed),
// 2 usage error, 3 cannot connect / no answer. The subcommands are in
// cmd_*.cpp, one function each (cli.hpp).
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "cli.hpp"

using namespace homingctl;

namespace {

void add_global_options(CLI::App& app, Context& ctx) {
  ConnectionOptions& co = ctx.co;
  app.add_option("--tcp", co.tcp, "Modbus TCP address HOST:PORT")->capture_default_str();
  app.add_option("--rtu", co.rtu, "Modbus RTU serial device (instead of TCP)");
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
  add_history_command(commands);
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
  const Run* command = commands.chosen();
  return command ? run(*command, ctx) : kOk;
}
