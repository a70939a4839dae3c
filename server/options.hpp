#pragma once
// homingd's start-up options: command line and TOML config file (--config),
// the command line winning. Fixed by the spec so any tool can start it.
#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "poll_window.hpp"
#include "registers/codec.hpp"

namespace server {

struct Options {
  bool tcp_enabled = true;
  std::string tcp_host = "127.0.0.1";
  int tcp_port = 1502;
  std::string rtu_device;  // empty: no RTU
  int baud = 19200;
  char parity = 'E';
  int stop_bits = 1;
  // A serial master silent this long releases the jog buttons it holds (0: never).
  int rtu_jog_release_ms = 1000;
  int unit_id = 1;
  std::string db_path = "homingd.db";
  std::string backend = "sim";
  int period_us = 1000;
  int rt_priority = 20;  // SCHED_FIFO for the control thread; 0 = normal scheduling
  registers::WordOrder word_order = registers::WordOrder::high_first;
  int max_clients = 32;
  int max_clients_per_address = 0;  // 0: as many as max_clients
  std::vector<std::string> privileged;  // addresses that never give way: "192.168.1.10", "10.0.0.0/24"
  int idle_timeout_s = 60;
  int poll_us = kDefaultPollUs;  // server/poll_window.hpp
  int sim_unit_id = 247;
  double time_scale = 1.0;
  std::string log_level = "info";
  std::string config_path;
  // Access: TCP clients allowed to write (empty = all); others may only read.
  std::vector<std::string> write_allow;  // "192.168.1.10", "10.0.0.0/24"
  std::int64_t unlock_code = 0;          // 0 = no settings lock; up to 32 bits
  int unlock_lockout_s = 10;             // the first lockout after too many wrong codes in a row
  int unlock_lockout_max_s = 900;        // the lockout doubles up to this
  int refusal_log_interval_s = 10;       // refused writes: one line per client and reason per interval
  // Modbus/TCP Security (TLS) beside TCP and RTU: off unless --tls is given.
  bool tls_enabled = false;
  std::string tls_host;
  int tls_port = 802;       // mbaps
  std::string tls_cert;     // the module's certificate (PEM)
  std::string tls_key;      // its private key
  std::string tls_ca;       // the CA that signs client certificates
  std::string tls_crl;      // revoked client certificates; empty: none
  std::string tls_default_role = "viewer";  // of a certificate without a role; "none": refused
  // Device identity (FC 43, FC 17); empty: the built-in text.
  std::string vendor_name;
  std::string vendor_url;
  std::string product_name;
  std::string machine_name;
  // MQTT / Sparkplug B edge node (docs/mqtt-sparkplug.md): off unless --mqtt is given.
  bool mqtt_enabled = false;
  std::string mqtt_host;
  int mqtt_port = 1883;
  std::string mqtt_group = "homing";  // Sparkplug group id
  std::string mqtt_node;              // edge node id; empty: --machine-name, else the host name
  int mqtt_keepalive_s = 30;
  bool mqtt_tls = false;              // mqtts://: TLS to the broker, its certificate checked against mqtt_ca
  std::string mqtt_ca;                // CA that signs the broker's certificate (PEM)
  std::string mqtt_cert;              // the module's client certificate (PEM), with mqtt_key
  std::string mqtt_key;
  std::string mqtt_user;              // MQTT user name; its password comes from mqtt_password_file
  std::string mqtt_password_file;
  std::string mqtt_outbox;            // events owed to the broker; empty: <db>.mqtt-events
  int mqtt_outbox_max = 10000;        // events kept at most while the broker is away (oldest dropped)
  std::string mqtt_primary_host;      // Sparkplug primary host id: publish only while its STATE says online
  bool mqtt_commands = false;         // NCMD cmd.* accepted (off: refused and reported)
  // Report by exception (sparkplug::ReportPolicy): positions and other lengths
  // move this far (mm, deg on rotary axes) before they are published again,
  // at most every mqtt_min_interval_ms; diagnostics at most every
  // mqtt_diagnostics_interval_ms; the module is looked at every mqtt_sample_ms.
  double mqtt_deadband = 0.01;
  int mqtt_min_interval_ms = 100;
  int mqtt_diagnostics_interval_ms = 10000;
  int mqtt_sample_ms = 50;
  // Offline settings transfer: act on --db and exit without serving.
  std::string export_settings;
  std::string import_settings;
};

// An IPv4 network for --write-allow.
struct Cidr {
  std::uint32_t network = 0;  // host byte order
  std::uint32_t mask = 0;
  // address: "a.b.c.d" or "a.b.c.d:port"
  bool contains(const std::string& address) const;
};
std::optional<Cidr> parse_cidr(const std::string& text);

struct ParseOutcome {
  Options options;
  bool exit_now = false;  // --help or --version was printed
  int exit_code = 0;
};

// The parser of the command line and the config file. Its option table is the
// costly part to build (CLI11), so one parser can parse any number of command
// lines, each from the defaults: homingd parses one, the config fuzzer
// (fuzz/fuzz_config.cpp) one per input.
class OptionParser {
 public:
  OptionParser();
  ~OptionParser();
  OptionParser(const OptionParser&) = delete;
  OptionParser& operator=(const OptionParser&) = delete;

  // Errors name the option and the accepted values.
  std::expected<ParseOutcome, std::string> parse(int argc, char** argv);

 private:
  struct Table;
  std::unique_ptr<Table> table_;
};

// One command line with a parser of its own.
std::expected<ParseOutcome, std::string> parse_options(int argc, char** argv);

}  // namespace server
