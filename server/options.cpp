#include "options.hpp"

#include <arpa/inet.h>

#include <CLI/CLI.hpp>

#include "config_file.hpp"
#include "tls/address.hpp"

namespace server {
namespace {

// Where --tcp and --tls listen: an IPv4 address of this computer. libmodbus
// reads it with inet_addr(), which takes a host name or a mistyped address
// (192.168.1.300) for 255.255.255.255 and listens where no client reaches.
std::expected<void, std::string> check_listen_address(const std::string& option, const std::string& host) {
  in_addr addr{};
  if (inet_pton(AF_INET, host.c_str(), &addr) != 1 || addr.s_addr == INADDR_BROADCAST)
    return std::unexpected(option + ": '" + host + "' is not an IPv4 address to listen on: give one of this "
                           "computer's addresses, 0.0.0.0 for all of them or 127.0.0.1 for this computer only "
                           "(host names are not accepted)");
  return {};
}

// --tls and its files come together: the files alone would serve nothing.
std::expected<void, std::string> check_tls(const Options& o, const CLI::App& app) {
  if (!o.tls_enabled) {
    for (const char* name : {"--tls-cert", "--tls-key", "--tls-ca", "--tls-crl", "--tls-default-role"})
      if (app.get_option(name)->count() > 0)
        return std::unexpected(std::string(name) + " is set but --tls is not: add --tls HOST[:PORT] to serve "
                               "Modbus/TCP Security");
    return {};
  }
  if (o.tls_cert.empty() || o.tls_key.empty() || o.tls_ca.empty())
    return std::unexpected("--tls needs --tls-cert, --tls-key and --tls-ca: the module's certificate, its key, and "
                           "the CA that signs client certificates");
  return {};
}

// --mqtt and what goes with it: the scheme decides TLS and the default port;
// the TLS files only with mqtts://, a client certificate only with its key,
// a password file only with a user name.
std::expected<void, std::string> check_mqtt(const std::string& url, Options& o, const CLI::App& app) {
  const auto given = [&](const char* name) { return app.get_option(name)->count() > 0; };
  if (url.empty()) {
    for (const char* name : {"--mqtt-node", "--mqtt-group", "--mqtt-keepalive-s", "--mqtt-ca", "--mqtt-cert",
                             "--mqtt-key", "--mqtt-user", "--mqtt-password-file", "--mqtt-outbox", "--mqtt-outbox-max",
                             "--mqtt-primary-host", "--mqtt-commands", "--mqtt-deadband",
                             "--mqtt-min-interval-ms", "--mqtt-diagnostics-interval-ms", "--mqtt-sample-ms"})
      if (given(name))
        return std::unexpected(std::string(name) + " is set but --mqtt is not: add --mqtt mqtt://HOST:PORT to publish");
    return {};
  }
  const bool tls = url.starts_with("mqtts://");
  if (!tls && !url.starts_with("mqtt://"))
    return std::unexpected("--mqtt " + url + ": expected mqtt://HOST[:PORT] or mqtts://HOST[:PORT], e.g. mqtt://broker.plant:1883");
  auto where = tls::split_host_port("--mqtt", url.substr(tls ? 8 : 7), tls ? 8883 : 1883);
  if (!where) return std::unexpected(where.error());
  o.mqtt_enabled = true;
  o.mqtt_tls = tls;
  o.mqtt_host = where->host;
  o.mqtt_port = where->port;
  if (tls && o.mqtt_ca.empty())
    return std::unexpected("--mqtt " + url + " needs --mqtt-ca: the CA certificate that signs the broker's certificate "
                           "(without it the broker could not be checked)");
  if (!tls)
    for (const char* name : {"--mqtt-ca", "--mqtt-cert", "--mqtt-key"})
      if (given(name))
        return std::unexpected(std::string(name) + " is set but --mqtt " + url +
                               " is plain MQTT: use mqtts://HOST:PORT for TLS to the broker");
  if (o.mqtt_cert.empty() != o.mqtt_key.empty())
    return std::unexpected("--mqtt-cert and --mqtt-key go together: the client certificate and its private key");
  if (!o.mqtt_password_file.empty() && o.mqtt_user.empty())
    return std::unexpected("--mqtt-password-file needs --mqtt-user: the user name the password belongs to");
  return {};
}

// CLI::Range on a whole-number option answers a fraction (unit = 1.5 in the
// config file) with "Value 1.5 not in range 1 to 247": say what is expected.
CLI::Validator whole_range(std::int64_t lo, std::int64_t hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        // Read as CLI11 then stores it (0x.. hex, a leading 0 octal), so that
        // the value checked is the value used.
        std::int64_t v = 0;
        if (!CLI::detail::lexical_cast(text, v) || v < lo || v > hi)
          return "expected a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) + ", got '" +
                 text + "'";
        return "";
      },
      "INT in [" + std::to_string(lo) + " - " + std::to_string(hi) + "]");
}

// A file option given as "" (db = "" in the config file) names no file.
CLI::Validator non_empty_path() {
  return CLI::Validator([](std::string& text) -> std::string { return text.empty() ? "empty path: give a file name" : ""; },
                        "PATH");
}

}  // namespace

std::optional<Cidr> parse_cidr(const std::string& text) {
  const auto slash = text.find('/');
  const std::string ip = text.substr(0, slash);
  in_addr addr{};
  if (inet_pton(AF_INET, ip.c_str(), &addr) != 1) return std::nullopt;
  int bits = 32;
  if (slash != std::string::npos) {
    try {
      std::size_t used = 0;
      bits = std::stoi(text.substr(slash + 1), &used);
      if (used != text.size() - slash - 1) return std::nullopt;
    } catch (const std::exception&) {
      return std::nullopt;
    }
    if (bits < 0 || bits > 32) return std::nullopt;
  }
  const std::uint32_t mask = bits == 0 ? 0 : ~std::uint32_t{0} << (32 - bits);
  return Cidr{ntohl(addr.s_addr) & mask, mask};
}

bool Cidr::contains(const std::string& address) const {
  const std::string ip = address.substr(0, address.rfind(':'));
  in_addr addr{};
  if (inet_pton(AF_INET, ip.c_str(), &addr) != 1) return false;
  return (ntohl(addr.s_addr) & mask) == network;
}

// The CLI11 option table, bound to the values one parse fills in.
struct OptionParser::Table {
  CLI::App app{"homingd: Modbus TCP/RTU homing module (simulator or GPIO backend)", "homingd"};
  Options o;
  std::string tcp = "127.0.0.1:1502";
  std::string tls;  // empty: no Modbus/TCP Security
  std::string mqtt;  // empty: no MQTT
  std::string parity = "E";
  std::string word_order = "high-first";
  // A bool flag: CLI11 2.1's integer flag callback throws std::invalid_argument
  // (uncaught: abort) on a value like `--no-tcp=yess` or `no-tcp = "on?"`.
  bool no_tcp = false;

  Table();
  // Back to the defaults, nothing parsed.
  void reset() {
    o = Options{};
    tcp = "127.0.0.1:1502";
    tls.clear();
    mqtt.clear();
    parity = "E";
    word_order = "high-first";
    no_tcp = false;
    app.clear();
  }
};

// Device identification objects are ASCII strings a reply can carry.
const CLI::Validator identity_text(
    [](const std::string& text) -> std::string {
      if (text.size() > 100) return "at most 100 characters";
      for (unsigned char ch : text)
        if (ch < 0x20 || ch > 0x7E) return "printable ASCII only (device identification objects are ASCII)";
      return {};
    },
    "TEXT");

// Sparkplug ids are topic levels: no wildcards, no separators, not empty.
const CLI::Validator sparkplug_id(
    [](const std::string& text) -> std::string {
      if (text.empty()) return "must not be empty";
      if (text.size() > 64) return "at most 64 characters";
      for (unsigned char ch : text)
        if (ch == '/' || ch == '+' || ch == '#' || ch < 0x21 || ch > 0x7E)
          return "printable ASCII without '/', '+', '#' or spaces (it is an MQTT topic level)";
      return {};
    },
    "ID");

OptionParser::Table::Table() {
  app.set_version_flag("--version", "homingd " HOMING_VERSION);
  app.config_formatter(std::make_shared<ConfigFileReader>(app));
  app.set_config("--config", "", "TOML config file; every option below can be a key in it")
      ->check(CLI::ExistingFile);
  app.add_option("--tcp", tcp, "Modbus TCP listen address HOST:PORT")->capture_default_str();
  app.add_flag("--no-tcp,--no_tcp", no_tcp, "No plain Modbus TCP: serve RTU and/or TLS only");
  app.add_option("--tls", tls,
                 "Modbus/TCP Security (TLS, client certificates) listen address HOST[:PORT], port 802 when not "
                 "given; served beside TCP and RTU");
  app.add_option("--tls-cert,--tls_cert", o.tls_cert, "The module's TLS certificate (PEM)");
  app.add_option("--tls-key,--tls_key", o.tls_key, "The private key of --tls-cert (PEM, no pass phrase)");
  app.add_option("--tls-ca,--tls_ca", o.tls_ca, "The CA certificate that signs client certificates (PEM)");
  app.add_option("--tls-crl,--tls_crl", o.tls_crl, "Revoked client certificates (PEM CRL of that CA)");
  app.add_option("--tls-default-role,--tls_default_role", o.tls_default_role,
                 "Role of a client certificate without the role extension; none: refuse it")
      ->check(CLI::IsMember({"viewer", "operator", "engineer", "none"}))
      ->capture_default_str();
  app.add_option("--rtu", o.rtu_device, "Serial device for Modbus RTU (e.g. /dev/ttyUSB0)");
  app.add_option("--baud", o.baud, "RTU baud rate")
      ->check(CLI::IsMember({1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200}))
      ->capture_default_str();
  app.add_option("--parity", parity, "RTU parity")->check(CLI::IsMember({"N", "E", "O"}))->capture_default_str();
  app.add_option("--stop-bits,--stop_bits", o.stop_bits, "RTU stop bits")->check(CLI::IsMember({1, 2}))->capture_default_str();
  app.add_option("--rtu-jog-release-ms,--rtu_jog_release_ms", o.rtu_jog_release_ms,
                 "Over RTU, the jog buttons the master holds are released when no request for the module has come "
                 "for this long (a serial line has no disconnect: a dead panel's jog stops); above the master's "
                 "poll cycle; 0: never")
      ->check(whole_range(0, 60000))
      ->capture_default_str();
  app.add_option("--unit", o.unit_id, "Modbus unit id of the module")->check(whole_range(1, 247))->capture_default_str();
  app.add_option("--db", o.db_path, "SQLite settings database")->check(non_empty_path())->capture_default_str();
  app.add_option("--backend", o.backend, "Machine I/O backend")
      ->check(CLI::IsMember({"sim", "gpiod"}))
      ->capture_default_str();
  app.add_option("--period-us,--period_us", o.period_us, "Control period in microseconds")
      ->check(whole_range(100, 100000))
      ->capture_default_str();
  app.add_option("--rt-priority,--rt_priority", o.rt_priority,
                 "SCHED_FIFO priority of the control loop thread (1..99); 0 = normal scheduling")
      ->check(whole_range(0, 99))
      ->capture_default_str();
  app.add_option("--word-order,--word_order", word_order, "Order of the two words of 32-bit values")
      ->check(CLI::IsMember({"high-first", "low-first"}))
      ->capture_default_str();
  app.add_option("--max-clients,--max_clients", o.max_clients, "Maximum simultaneous TCP clients")
      ->check(whole_range(1, 1024))
      ->capture_default_str();
  app.add_option("--max-clients-per-address,--max_clients_per_address", o.max_clients_per_address,
                 "Maximum simultaneous TCP clients from one address; 0: as many as --max-clients")
      ->check(whole_range(0, 1024))
      ->capture_default_str();
  app.add_option("--privileged", o.privileged,
                 "Privileged TCP client addresses (the PLC, the HMI; IPv4 address or CIDR, comma separated): their "
                 "connections never give way, and when the server is full one of another client is closed for them")
      ->delimiter(',');
  app.add_option("--idle-timeout-s,--idle_timeout_s", o.idle_timeout_s, "Drop a TCP client silent for this long")
      ->check(whole_range(1, 86400))
      ->capture_default_str();
  app.add_option("--poll-us,--poll_us", o.poll_us,
                 "After a turn in which it answered a client, a TCP/TLS event loop polls for the next request up to "
                 "this long before it sleeps (learnt from the traffic, per loop: back-to-back requests answer sooner, "
                 "slow pollers cost nothing); 0: never poll")
      ->check(whole_range(0, 1000))
      ->capture_default_str();
  app.add_option("--sim-unit,--sim_unit", o.sim_unit_id, "Unit id of the simulator (sim backend only)")
      ->check(whole_range(1, 247))
      ->capture_default_str();
  app.add_option("--time-scale,--time_scale", o.time_scale, "Simulated time runs this many times faster than the wall clock")
      ->check(CLI::Range(0.01, 1000.0))
      ->capture_default_str();
  app.add_option("--log-level,--log_level", o.log_level, "Log level")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}))
      ->capture_default_str();
  app.add_option("--write-allow,--write_allow", o.write_allow,
                 "TCP client addresses allowed to write (IPv4 address or CIDR, comma separated); others may "
                 "only read. Default: every client")
      ->delimiter(',');
  app.add_option("--unlock-code,--unlock_code", o.unlock_code,
                 "Lock settings writes until this code is written: 1..65535 to security.unlock (FC 06) or "
                 "security.unlock32, up to 4294967295 to security.unlock32 (both words in one FC 16 request)")
      ->check(whole_range(1, 4294967295LL));
  app.add_option("--unlock-lockout-s,--unlock_lockout_s", o.unlock_lockout_s,
                 "After 5 wrong unlock codes in a row every unlock is refused for this long, doubling with each "
                 "further wrong code")
      ->check(whole_range(1, 86400))
      ->capture_default_str();
  app.add_option("--unlock-lockout-max-s,--unlock_lockout_max_s", o.unlock_lockout_max_s,
                 "The longest lockout of the unlock code")
      ->check(whole_range(1, 86400))
      ->capture_default_str();
  app.add_option("--refusal-log-interval-s,--refusal_log_interval_s", o.refusal_log_interval_s,
                 "Refused writes and connections: the first of a client and reason is logged whole, the rest as "
                 "one count per client and reason every this many seconds")
      ->check(whole_range(1, 3600))
      ->capture_default_str();
  app.add_option("--vendor-name,--vendor_name", o.vendor_name,
                 "Vendor name the module reports (FC 43 object 0)")
      ->check(identity_text);
  app.add_option("--vendor-url,--vendor_url", o.vendor_url, "Vendor URL the module reports (FC 43 object 3)")
      ->check(identity_text);
  app.add_option("--product-name,--product_name", o.product_name, "Product name the module reports (FC 43 object 4)")
      ->check(identity_text);
  app.add_option("--machine-name,--machine_name", o.machine_name,
                 "The machine's name, reported as the user application name (FC 43 object 6, FC 17)")
      ->check(identity_text);
  app.add_option("--mqtt", mqtt,
                 "Publish to this MQTT broker as a Sparkplug B edge node: mqtt://HOST[:PORT] (default port 1883) or, over "
                 "TLS, mqtts://HOST[:PORT] (default port 8883, needs --mqtt-ca)");
  app.add_option("--mqtt-group,--mqtt_group", o.mqtt_group, "Sparkplug group id")->check(sparkplug_id)->capture_default_str();
  app.add_option("--mqtt-node,--mqtt_node", o.mqtt_node,
                 "Sparkplug edge node id (default: --machine-name, else the host name)")
      ->check(sparkplug_id);
  app.add_option("--mqtt-keepalive-s,--mqtt_keepalive_s", o.mqtt_keepalive_s,
                 "MQTT keep-alive: the broker publishes the death certificate this long (x1.5) after the module falls silent")
      ->check(whole_range(5, 3600))
      ->capture_default_str();
  app.add_option("--mqtt-ca,--mqtt_ca", o.mqtt_ca,
                 "mqtts://: the CA certificate (PEM) that signs the broker's certificate; the broker's name or "
                 "IP must match it")
      ->check(CLI::ExistingFile);
  app.add_option("--mqtt-cert,--mqtt_cert", o.mqtt_cert,
                 "mqtts://: the module's client certificate (PEM), for brokers that require one (with --mqtt-key)")
      ->check(CLI::ExistingFile);
  app.add_option("--mqtt-key,--mqtt_key", o.mqtt_key, "mqtts://: the private key of --mqtt-cert (PEM, no pass phrase)")
      ->check(CLI::ExistingFile);
  app.add_option("--mqtt-user,--mqtt_user", o.mqtt_user, "MQTT user name (its password in --mqtt-password-file)");
  app.add_option("--mqtt-password-file,--mqtt_password_file", o.mqtt_password_file,
                 "File whose first line is the MQTT password of --mqtt-user (keep it readable by the service only)")
      ->check(CLI::ExistingFile);
  app.add_option("--mqtt-primary-host,--mqtt_primary_host", o.mqtt_primary_host,
                 "Sparkplug primary host id: be born and publish only while spBv1.0/STATE/<id> says online "
                 "(events wait in the outbox meanwhile)")
      ->check(sparkplug_id);
  app.add_flag("--mqtt-commands,--mqtt_commands", o.mqtt_commands,
               "Carry out commands sent as NCMD (cmd/home_all, cmd/abort, cmd/reset_alarm, ...) through the same "
               "interlocks as Modbus; off: refused and answered as an event");
  app.add_option("--mqtt-outbox,--mqtt_outbox", o.mqtt_outbox,
                 "SQLite file keeping homing cycles, alarms and settings changes until the broker has them, "
                 "and the last Sparkplug bdSeq (default: the --db path + .mqtt-events)");
  app.add_option("--mqtt-outbox-max,--mqtt_outbox_max", o.mqtt_outbox_max,
                 "Events kept at most while the broker is away; past it the oldest are dropped and counted")
      ->check(whole_range(100, 10000000))
      ->capture_default_str();
  app.add_option("--mqtt-deadband,--mqtt_deadband", o.mqtt_deadband,
                 "Positions and other lengths are published again once they moved this far from the value last "
                 "published (mm; deg on rotary axes)")
      ->check(CLI::Range(0.001, 1000.0))
      ->capture_default_str();
  app.add_option("--mqtt-min-interval-ms,--mqtt_min_interval_ms", o.mqtt_min_interval_ms,
                 "A moving position is published at most this often (ms); other values as they change")
      ->check(whole_range(0, 60000))
      ->capture_default_str();
  app.add_option("--mqtt-diagnostics-interval-ms,--mqtt_diagnostics_interval_ms", o.mqtt_diagnostics_interval_ms,
                 "Loop timing and resource figures (diag.*) are published at most this often (ms)")
      ->check(whole_range(1000, 3600000))
      ->capture_default_str();
  app.add_option("--mqtt-sample-ms,--mqtt_sample_ms", o.mqtt_sample_ms,
                 "How often the edge node looks at the module for changes and events to publish (ms)")
      ->check(whole_range(10, 10000))
      ->capture_default_str();
  app.add_option("--export-settings,--export_settings", o.export_settings,
                 "Write every setting of --db to this TOML file and exit (no server)");
  app.add_option("--import-settings,--import_settings", o.import_settings,
                 "Validate this TOML file like Modbus writes, apply it to --db in one transaction and exit")
      ->check(CLI::ExistingFile);
}

OptionParser::OptionParser() : table_(std::make_unique<Table>()) {}
OptionParser::~OptionParser() = default;

std::expected<ParseOutcome, std::string> OptionParser::parse(int argc, char** argv) {
  Table& t = *table_;
  t.reset();
  CLI::App& app = t.app;
  ParseOutcome out;
  // The path as given: as<std::string>() would validate it again, and throw
  // once more for a file that does not exist (an abort, not an answer).
  const auto config_given = [&app] {
    const CLI::Option* cfg = app.get_option("--config");
    return cfg->results().empty() ? std::string() : cfg->results().front();
  };
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    out.exit_now = true;
    out.exit_code = app.exit(e);
    return out;
  } catch (const CLI::CallForVersion& e) {
    out.exit_now = true;
    out.exit_code = app.exit(e);
    return out;
  } catch (const ConfigFileError& e) {
    return std::unexpected("--config " + config_given() + ": " + e.what());
  } catch (const CLI::ParseError& e) {
    std::string what = e.what();
    if (const std::string cfg = config_given(); !cfg.empty() && what.find(cfg) == std::string::npos)
      what += " (config file " + cfg + ")";
    return std::unexpected(what);
  }
  out.options = t.o;
  Options& o = out.options;
  if (t.no_tcp) o.tcp_enabled = false;
  if (auto cfg = app.get_option("--config"); cfg->count() > 0) {
    o.config_path = cfg->as<std::string>();
  }
  if (o.tcp_enabled) {
    auto where = tls::split_host_port("--tcp", t.tcp, std::nullopt);
    if (!where) return std::unexpected(where.error());
    if (auto ok = check_listen_address("--tcp", where->host); !ok) return std::unexpected(ok.error());
    o.tcp_host = where->host;
    o.tcp_port = where->port;
  }
  if (!t.tls.empty()) {
    auto where = tls::split_host_port("--tls", t.tls, 802);
    if (!where) return std::unexpected(where.error());
    if (auto ok = check_listen_address("--tls", where->host); !ok) return std::unexpected(ok.error());
    o.tls_enabled = true;
    o.tls_host = where->host;
    o.tls_port = where->port;
  }
  if (auto r = check_tls(o, app); !r) return std::unexpected(r.error());
  if (auto r = check_mqtt(t.mqtt, o, app); !r) return std::unexpected(r.error());
  o.parity = t.parity.empty() ? 'E' : t.parity[0];
  o.word_order = t.word_order == "low-first" ? registers::WordOrder::low_first : registers::WordOrder::high_first;
  for (const auto& entry : o.write_allow)
    if (!parse_cidr(entry)) return std::unexpected("--write-allow: '" + entry + "' is not an IPv4 address or CIDR (e.g. 10.0.0.0/24)");
  for (const auto& entry : o.privileged)
    if (!parse_cidr(entry)) return std::unexpected("--privileged: '" + entry + "' is not an IPv4 address or CIDR (e.g. 10.0.0.5 or 10.0.0.0/29)");
  if (o.unlock_lockout_max_s < o.unlock_lockout_s)
    return std::unexpected("--unlock-lockout-max-s " + std::to_string(o.unlock_lockout_max_s) +
                           " is below --unlock-lockout-s " + std::to_string(o.unlock_lockout_s) +
                           ": the longest lockout cannot be shorter than the first");
  if (!o.tcp_enabled && o.rtu_device.empty() && !o.tls_enabled)
    return std::unexpected("--no-tcp needs --rtu DEVICE or --tls HOST[:PORT]: with neither, nothing would be served");
  if (o.sim_unit_id == o.unit_id && o.backend == "sim")
    return std::unexpected("--sim-unit " + std::to_string(o.sim_unit_id) + " must differ from --unit " +
                           std::to_string(o.unit_id));
  return out;
}

std::expected<ParseOutcome, std::string> parse_options(int argc, char** argv) {
  return OptionParser().parse(argc, argv);
}

}  // namespace server
