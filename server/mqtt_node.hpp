#pragma once
// The Sparkplug B edge node on an MQTT broker (libmosquitto). Two threads of
// its own: libmosquitto's network loop (connect, reconnect, NCMD) and the
// publisher, which samples the module the way a Modbus read does
// (ModbusService::with_module_view over the loop's published snapshot) and
// publishes NBIRTH / NDATA by exception. The control loop never waits for it:
// a slow or absent broker only delays this node's own messages.
#include <atomic>
#include <cstdint>
#include <expected>
#include <set>
#include <string>
#include <map>
#include <mutex>
#include <thread>

#include "modbus_service.hpp"
#include "options.hpp"
#include "persistence/event_outbox.hpp"
#include "refusal_log.hpp"
#include "sparkplug/host_state.hpp"
#include "sparkplug/payload.hpp"

struct mosquitto;
struct mosquitto_message;

namespace server {

struct MqttConfig {
  std::string host;
  int port = 1883;
  std::string group;
  std::string node;
  int keepalive_s = 30;
  int sample_ms = 50;  // how often the publisher looks for changes
  sparkplug::ReportPolicy report;  // what counts as a change worth publishing
  bool tls = false;
  std::string ca, cert, key;  // PEM files (cert and key: a client certificate, both or neither)
  std::string user, password;  // empty user: no user name sent
  std::string primary_host;    // empty: publish whenever connected
  bool commands = false;       // NCMD cmd.* carried out (else refused and reported)
  std::string outbox;          // the event outbox's file
  std::size_t outbox_max = 10000;
  // Refused or ignored NCMDs in the log: the first of each reason whole, the
  // rest counted per interval (--refusal-log-interval-s), as refused writes.
  std::chrono::seconds refusal_log_interval{10};
};
// From the daemon's options; the node id defaults to the machine name, else
// the host name. The password is read from its file here: an unreadable or
// empty file is an error that names it.
std::expected<MqttConfig, std::string> mqtt_config(const Options& options);

class MqttNode {
 public:
  // outbox: the plant events owed to the broker (nullptr: values only).
  MqttNode(MqttConfig config, ModbusService& service, persistence::EventOutbox* outbox = nullptr);
  ~MqttNode();  // stop()
  MqttNode(const MqttNode&) = delete;
  MqttNode& operator=(const MqttNode&) = delete;

  void start();
  // Clean stop: NDEATH is published (the broker would send the Will only on a
  // lost connection), then the connection is closed.
  void stop();

  std::string topic(std::string_view type) const;  // spBv1.0/<group>/<type>/<node>

 private:
  static void on_connect(mosquitto*, void* self, int rc);
  static void on_disconnect(mosquitto*, void* self, int rc);
  static void on_message(mosquitto*, void* self, const mosquitto_message* msg);
  static void on_log(mosquitto*, void* self, int level, const char* text);
  static void on_publish(mosquitto*, void* self, int mid);
  void send_events(sparkplug::EdgeNode& node);
  void set_will();
  void network_loop();
  void on_session_lost(int rc);
  void log_once(const std::string& text);
  bool may_publish();  // connected, and the primary host (if any) online
  void take_host_state(const mosquitto_message* msg);
  void take_command(const std::string& metric, bool on);
  // A refused or ignored NCMD: its line, or its count in the next summary.
  void ncmd_refused(const std::string& reason, const std::string& line);
  std::pair<std::int64_t, std::int64_t> judged();
  void publish_loop();
  bool publish(std::string_view type, const std::string& bytes);
  void take_bd_seq(bool first);

  MqttConfig config_;
  ModbusService& service_;
  mosquitto* mosq_ = nullptr;
  std::atomic<std::uint64_t> bd_seq_{0};   // of the current (or next) session
  std::atomic<bool> connected_{false};
  std::atomic<bool> need_birth_{false};    // a new session, or a rebirth asked for
  std::atomic<bool> stop_{false};
  std::atomic<bool> stop_network_{false};
  std::thread network_;
  bool started_ = false;
  std::thread publisher_;
  persistence::EventOutbox* outbox_;
  std::mutex host_mutex_;
  sparkplug::PrimaryHost host_;               // the primary host's STATE (when configured)
  std::atomic<bool> host_gone_{false};        // went offline while born: death, then a new session
  std::atomic<bool> resend_all_{true};  // the connection was lost: what was in flight may not have arrived
  std::int64_t sent_through_ = 0;  // publisher thread: events handed to libmosquitto this session
  std::uint64_t birth_ms_ = 0;     // publisher thread: this session's birth; an older event is historical
  std::mutex flight_mutex_;
  std::map<int, std::int64_t> in_flight_;  // message id -> event id, until written to the broker
  std::mutex log_mutex_;
  std::set<std::string> logged_reasons_;  // why connecting failed, each logged once since the last session
  std::mutex ncmd_log_mutex_;             // the network thread logs, the publisher flushes
  RefusalLog ncmd_log_;
};

}  // namespace server
