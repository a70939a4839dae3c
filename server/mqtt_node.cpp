#include "mqtt_node.hpp"

#include <mosquitto.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <spdlog/spdlog.h>

#include "sparkplug/payload.hpp"

namespace server {
namespace {

std::int64_t now_ms() {
  using namespace std::chrono;
  return duration_cast<milliseconds>(system_clock::now().time_since_epoch()).count();
}

// A machine or host name as a topic level: what MQTT forbids there becomes '_'.
std::string as_node_id(std::string text) {
  for (char& ch : text)
    if (ch == '/' || ch == '+' || ch == '#' || static_cast<unsigned char>(ch) <= 0x20 || static_cast<unsigned char>(ch) > 0x7E)
      ch = '_';
  return text.empty() ? std::string("homingd") : text;
}

struct LibInit {
  LibInit() { mosquitto_lib_init(); }
  ~LibInit() { mosquitto_lib_cleanup(); }
};

}  // namespace

// The first line of the file, without its line end: what `echo secret > file` writes.
std::expected<std::string, std::string> read_password(const std::string& path) {
  std::ifstream in(path);
  if (!in) return std::unexpected("--mqtt-password-file " + path + ": cannot be read (" + std::strerror(errno) + ")");
  std::string line;
  std::getline(in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (line.empty()) return std::unexpected("--mqtt-password-file " + path + ": the first line is empty; write the password there");
  struct stat st{};
  if (stat(path.c_str(), &st) == 0 && (st.st_mode & (S_IRWXG | S_IRWXO)))
    spdlog::warn("mqtt: {} can be read by others (mode {:o}); chmod 600 it", path, st.st_mode & 0777);
  return line;
}

std::expected<MqttConfig, std::string> mqtt_config(const Options& o) {
  MqttConfig c;
  c.tls = o.mqtt_tls;
  c.ca = o.mqtt_ca;
  c.cert = o.mqtt_cert;
  c.key = o.mqtt_key;
  c.user = o.mqtt_user;
  if (!o.mqtt_password_file.empty()) {
    auto pw = read_password(o.mqtt_password_file);
    if (!pw) return std::unexpected(pw.error());
    c.password = *pw;
  }
  c.host = o.mqtt_host;
  c.port = o.mqtt_port;
  c.group = o.mqtt_group;
  c.keepalive_s = o.mqtt_keepalive_s;
  if (!o.mqtt_node.empty()) {
    c.node = o.mqtt_node;
  } else if (!o.machine_name.empty()) {
    c.node = as_node_id(o.machine_name);
  } else {
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    c.node = as_node_id(host);
  }
  return c;
}

MqttNode::MqttNode(MqttConfig config, ModbusService& service) : config_(std::move(config)), service_(service) {
  static LibInit lib;
  const std::string client_id = "homingd-" + config_.group + "-" + config_.node;
  mosq_ = mosquitto_new(client_id.c_str(), true, this);
  if (!mosq_) throw std::runtime_error("mqtt: cannot create the MQTT client (out of memory?)");
  mosquitto_connect_callback_set(mosq_, &MqttNode::on_connect);
  mosquitto_disconnect_callback_set(mosq_, &MqttNode::on_disconnect);
  mosquitto_message_callback_set(mosq_, &MqttNode::on_message);
  mosquitto_log_callback_set(mosq_, &MqttNode::on_log);
  mosquitto_reconnect_delay_set(mosq_, 1, 30, true);
  if (!config_.user.empty()) {
    const int rc = mosquitto_username_pw_set(mosq_, config_.user.c_str(),
                                             config_.password.empty() ? nullptr : config_.password.c_str());
    if (rc != MOSQ_ERR_SUCCESS) throw std::runtime_error(std::string("mqtt: user name: ") + mosquitto_strerror(rc));
  }
  if (config_.tls) {
    // The broker's certificate is checked against the CA and its name or IP
    // against the host of --mqtt (libmosquitto's default; never turned off).
    const int rc = mosquitto_tls_set(mosq_, config_.ca.c_str(), nullptr, config_.cert.empty() ? nullptr : config_.cert.c_str(),
                                     config_.key.empty() ? nullptr : config_.key.c_str(), nullptr);
    if (rc != MOSQ_ERR_SUCCESS)
      throw std::runtime_error("mqtt: TLS files (--mqtt-ca " + config_.ca + (config_.cert.empty() ? "" : ", --mqtt-cert " + config_.cert) +
                               (config_.key.empty() ? "" : ", --mqtt-key " + config_.key) + "): " + mosquitto_strerror(rc) +
                               " (are they PEM, and the key unencrypted?)");
  }
}

MqttNode::~MqttNode() {
  stop();
  mosquitto_destroy(mosq_);
}

std::string MqttNode::topic(std::string_view type) const {
  return "spBv1.0/" + config_.group + "/" + std::string(type) + "/" + config_.node;
}

// The Will carries the bdSeq of the session it is registered with, so a host
// can tell which birth the death belongs to.
void MqttNode::set_will() {
  const std::string bytes = sparkplug::EdgeNode::death(bd_seq_.load()).SerializeAsString();
  mosquitto_will_set(mosq_, topic("NDEATH").c_str(), static_cast<int>(bytes.size()), bytes.data(), 1, false);
}

void MqttNode::start() {
  set_will();
  const int rc = mosquitto_connect_async(mosq_, config_.host.c_str(), config_.port, config_.keepalive_s);
  if (rc != MOSQ_ERR_SUCCESS)
    spdlog::warn("mqtt: connecting to {}:{}: {}; retrying in the background", config_.host, config_.port,
                 mosquitto_strerror(rc));
  if (mosquitto_loop_start(mosq_) != MOSQ_ERR_SUCCESS)
    throw std::runtime_error("mqtt: cannot start the MQTT network thread");
  started_ = true;
  publisher_ = std::thread([this] { publish_loop(); });
  spdlog::info("mqtt: Sparkplug B edge node {} on {}://{}:{}{}", topic("NBIRTH"), config_.tls ? "mqtts" : "mqtt",
               config_.host, config_.port, config_.user.empty() ? "" : " as user " + config_.user);
}

void MqttNode::stop() {
  if (!started_) return;
  started_ = false;
  stop_ = true;
  if (publisher_.joinable()) publisher_.join();
  if (connected_) {
    const std::string bytes = sparkplug::EdgeNode::death(bd_seq_.load()).SerializeAsString();
    int mid = 0;
    mosquitto_publish(mosq_, &mid, topic("NDEATH").c_str(), static_cast<int>(bytes.size()), bytes.data(), 1, false);
  }
  mosquitto_disconnect(mosq_);
  mosquitto_loop_stop(mosq_, false);
}

void MqttNode::on_connect(mosquitto* m, void* self_ptr, int rc) {
  auto* self = static_cast<MqttNode*>(self_ptr);
  if (rc != 0) {
    spdlog::warn("mqtt: broker refused the connection: {}", mosquitto_connack_string(rc));
    return;
  }
  mosquitto_subscribe(m, nullptr, self->topic("NCMD").c_str(), 1);
  self->connected_ = true;
  self->need_birth_ = true;
  {
    std::lock_guard lock(self->log_mutex_);
    self->last_lib_error_.clear();
  }
  spdlog::info("mqtt: connected to {}:{} (bdSeq {})", self->config_.host, self->config_.port, self->bd_seq_.load());
}

// The next session gets the next bdSeq, and its Will says so before the
// reconnect registers it.
void MqttNode::on_disconnect(mosquitto*, void* self_ptr, int rc) {
  auto* self = static_cast<MqttNode*>(self_ptr);
  const bool was = self->connected_.exchange(false);
  self->bd_seq_ = (self->bd_seq_.load() + 1) % 256;
  self->set_will();
  if (was && rc != 0) spdlog::warn("mqtt: lost the broker ({}); reconnecting", mosquitto_strerror(rc));
}

// libmosquitto's own errors (a TLS handshake the broker refused, a
// certificate that does not verify): the why of a connection that fails. A
// line repeated on each reconnect attempt is logged once until another one.
void MqttNode::on_log(mosquitto*, void* self_ptr, int level, const char* text) {
  if (!(level & (MOSQ_LOG_ERR | MOSQ_LOG_WARNING)) || !text) return;
  auto* self = static_cast<MqttNode*>(self_ptr);
  std::lock_guard lock(self->log_mutex_);
  if (self->last_lib_error_ == text) return;
  self->last_lib_error_ = text;
  spdlog::warn("mqtt: {}:{}: {}", self->config_.host, self->config_.port, text);
}

void MqttNode::on_message(mosquitto*, void* self_ptr, const mosquitto_message* msg) {
  auto* self = static_cast<MqttNode*>(self_ptr);
  sparkplug::Payload cmd;
  if (!cmd.ParseFromArray(msg->payload, msg->payloadlen)) {
    spdlog::warn("mqtt: NCMD on {} is not a Sparkplug B payload; ignored", msg->topic);
    return;
  }
  for (const auto& metric : cmd.metrics()) {
    if (metric.name() == sparkplug::kRebirthName && metric.boolean_value()) {
      spdlog::info("mqtt: rebirth requested");
      self->need_birth_ = true;
    } else {
      spdlog::warn("mqtt: NCMD metric '{}' ignored: MQTT commands are not supported", metric.name());
    }
  }
}

bool MqttNode::publish(std::string_view type, const std::string& bytes) {
  const int rc = mosquitto_publish(mosq_, nullptr, topic(type).c_str(), static_cast<int>(bytes.size()),
                                   bytes.data(), 0, false);
  return rc == MOSQ_ERR_SUCCESS;
}

void MqttNode::publish_loop() {
  sparkplug::EdgeNode node;
  while (!stop_) {
    if (connected_) {
      service_.with_module_view([&](const registers::ModuleView& view) {
        const sparkplug::RawReader read = [&](const registers::Register& reg) { return registers::read_raw(reg, view); };
        if (need_birth_.exchange(false)) {
          if (!publish("NBIRTH", node.birth(bd_seq_.load(), read, static_cast<std::uint64_t>(now_ms())).SerializeAsString()))
            need_birth_ = true;  // not connected after all: born again on the next connection
        } else if (auto data = node.data(read, static_cast<std::uint64_t>(now_ms()))) {
          if (!publish("NDATA", data->SerializeAsString())) need_birth_ = true;
        }
      });
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(config_.sample_ms));
  }
}

}  // namespace server
