// homingd: the homing module's daemon (server/daemon.hpp), or, with
// --export-settings / --import-settings, a settings file transfer on its
// database (server/settings_file_mode.hpp). main only chooses.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>

#include "daemon.hpp"
#include "options.hpp"
#include "settings_file_mode.hpp"
#include "start_up.hpp"

namespace {

void start_logging(const std::string& level) {
  auto logger = spdlog::stderr_color_mt("homingd");
  spdlog::set_default_logger(logger);
  spdlog::set_level(spdlog::level::from_str(level));
  spdlog::set_pattern("%Y-%m-%d %H:%M:%S.%e %^%l%$ %v");
}

}  // namespace

int main(int argc, char** argv) {
  auto parsed = server::parse_options(argc, argv);
  if (!parsed) {
    std::fprintf(stderr, "homingd: %s\nRun 'homingd --help' for the options and their accepted values.\n",
                 parsed.error().c_str());
    return 2;
  }
  if (parsed->exit_now) return parsed->exit_code;
  const server::Options& opt = parsed->options;
  start_logging(opt.log_level);

  // The wiring is read first in every mode, so a mistake in the config file
  // is reported before anything else starts.
  const auto wiring = server::read_wiring(opt);
  if (!wiring) return server::fail_start(wiring.error());
  if (server::is_settings_file_mode(opt)) return server::run_settings_file_mode(opt);
  return server::run_daemon(opt, *wiring);
}
