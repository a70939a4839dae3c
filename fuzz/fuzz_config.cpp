// libFuzzer target: homingd's config file. The input is written to a
// temporary TOML file (on tmpfs when there is one) and parsed as
// `homingd --config FILE` does, by server::OptionParser (toml++ for the key
// check, CLI11 for the values): one parser for all inputs, as it is built to
// parse any number of command lines, each from the defaults. Then its [gpiod]
// table is read as `--backend gpiod` would read it. Besides "no
// crash" (no uncaught exception either): the result is an error message or
// options inside the documented ranges, never both nor neither.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "homing/gpiod/config.hpp"
#include "server/options.hpp"

namespace {

std::string config_path() {
  static const std::string path =
      (fuzz::scratch_dir() / ("homing-fuzz-config-" + std::to_string(::getpid()) + ".toml"))
          .string();
  return path;
}

void check(bool ok, const char* what) {
  if (!ok) fuzz::violated(what, 0, {});
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet_logs();
  fuzz::remove_stale_temp_files("homing-fuzz-config-");
  (void)config_path();  // constructed before the handler is registered: destroyed after it ran
  std::atexit([] { std::remove(config_path().c_str()); });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = config_path();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  std::vector<std::string> args{"homingd", "--config", path};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  static server::OptionParser parser;
  const auto parsed = parser.parse(static_cast<int>(args.size()), argv.data());
  if (!parsed) {
    check(!parsed.error().empty(), "an error without a message");
  } else {
    const server::Options& o = parsed->options;
    check(!parsed->exit_now, "a config file asked for --help or --version");
    check(o.config_path == path, "config path lost");
    check(!o.tcp_enabled || (o.tcp_port >= 1 && o.tcp_port <= 65535), "tcp port out of range");
    check(o.unit_id >= 1 && o.unit_id <= 247, "unit out of range");
    check(o.sim_unit_id >= 1 && o.sim_unit_id <= 247, "sim unit out of range");
    check(o.backend != "sim" || o.sim_unit_id != o.unit_id, "sim unit equals unit");
    check(o.period_us >= 100 && o.period_us <= 100000, "period out of range");
    check(o.max_clients >= 1 && o.max_clients <= 1024, "max clients out of range");
    check(o.idle_timeout_s >= 1 && o.idle_timeout_s <= 86400, "idle timeout out of range");
    check(o.time_scale >= 0.01 && o.time_scale <= 1000.0, "time scale out of range");
    check(o.parity == 'N' || o.parity == 'E' || o.parity == 'O', "parity");
    check(o.stop_bits == 1 || o.stop_bits == 2, "stop bits");
    check(o.unlock_code >= 0 && o.unlock_code <= 4294967295LL, "unlock code out of range");
    check(o.tcp_enabled || !o.rtu_device.empty() || o.tls_enabled, "nothing to serve");
    check(!o.tls_enabled || (o.tls_port >= 1 && o.tls_port <= 65535), "tls port out of range");
    check(!o.tls_enabled || (!o.tls_cert.empty() && !o.tls_key.empty() && !o.tls_ca.empty()), "tls without its files");
    check(o.tls_default_role == "viewer" || o.tls_default_role == "operator" || o.tls_default_role == "engineer" ||
              o.tls_default_role == "none",
          "tls default role");
    for (const auto& entry : o.write_allow) check(server::parse_cidr(entry).has_value(), "bad --write-allow entry");
    check(o.backend == "sim" || o.backend == "gpiod", "backend");
  }
  // The [gpiod] table (read only with --backend gpiod): an error or a config.
  const auto gpio = homing::gpiod::load_config(path);
  if (!gpio) check(!gpio.error().empty(), "a [gpiod] error without a message");
  return 0;
}
