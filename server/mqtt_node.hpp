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
#include <string>
#include <mutex>
#include <thread>

#include "modbus_service.hpp"
#include "options.hpp"

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
  bool tls = false;
  std::string ca, cert, key;  // PEM files (cert and key: a client certificate, both or neither)
  std::string user, password;  // empty user: no user name sent
};
// From the daemon's options; the node id defaults to the machine name, else
// the host name. The password is read from its file here: an unreadable or
// empty file is an error that names it.
std::expected<MqttConfig, std::string> mqtt_config(const Options& options);

class MqttNode {
 public:
  MqttNode(MqttConfig config, ModbusService& service);
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
  void set_will();
  void publish_loop();
  bool publish(std::string_view type, const std::string& bytes);

  MqttConfig config_;
  ModbusService& service_;
  mosquitto* mosq_ = nullptr;
  std::atomic<std::uint64_t> bd_seq_{0};   // of the current (or next) session
  std::atomic<bool> connected_{false};
  std::atomic<bool> need_birth_{false};    // a new session, or a rebirth asked for
  std::atomic<bool> stop_{false};
  bool started_ = false;
  std::thread publisher_;
  std::mutex log_mutex_;
  std::string last_lib_error_;  // the last libmosquitto error logged
};

}  // namespace server
