#include "mqtt_node.hpp"
#include "thread_name.hpp"

#include <mosquitto.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "registers/errors.hpp"
#include "registers/lookup.hpp"
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
  c.primary_host = o.mqtt_primary_host;
  c.commands = o.mqtt_commands;
  c.outbox = o.mqtt_outbox.empty() ? o.db_path + ".mqtt-events" : o.mqtt_outbox;
  c.outbox_max = static_cast<std::size_t>(o.mqtt_outbox_max);
  if (!o.mqtt_password_file.empty()) {
    auto pw = read_password(o.mqtt_password_file);
    if (!pw) return std::unexpected(pw.error());
    c.password = *pw;
  }
  c.host = o.mqtt_host;
  c.port = o.mqtt_port;
  c.group = o.mqtt_group;
  c.keepalive_s = o.mqtt_keepalive_s;
  c.sample_ms = o.mqtt_sample_ms;
  c.refusal_log_interval = std::chrono::seconds(o.refusal_log_interval_s);
  c.report.length_deadband = o.mqtt_deadband;
  c.report.length_min_interval_ms = static_cast<std::uint64_t>(o.mqtt_min_interval_ms);
  c.report.diagnostics_min_interval_ms = static_cast<std::uint64_t>(o.mqtt_diagnostics_interval_ms);
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

MqttNode::MqttNode(MqttConfig config, ModbusService& service, persistence::EventOutbox* outbox)
    : config_(std::move(config)),
      service_(service),
      outbox_(outbox),
      ncmd_log_("NCMDs", config_.refusal_log_interval,
                [](spdlog::level::level_enum level, const std::string& line) { spdlog::log(level, "{}", line); }) {
  static LibInit lib;
  const std::string client_id = "homingd-" + config_.group + "-" + config_.node;
  mosq_ = mosquitto_new(client_id.c_str(), true, this);
  if (!mosq_) throw std::runtime_error("mqtt: cannot create the MQTT client (out of memory?)");
  mosquitto_connect_callback_set(mosq_, &MqttNode::on_connect);
  mosquitto_disconnect_callback_set(mosq_, &MqttNode::on_disconnect);
  mosquitto_message_callback_set(mosq_, &MqttNode::on_message);
  mosquitto_log_callback_set(mosq_, &MqttNode::on_log);
  mosquitto_publish_callback_set(mosq_, &MqttNode::on_publish);
  mosquitto_threaded_set(mosq_, true);  // publishes come from the publisher thread
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

// Each MQTT CONNECT registers the next bdSeq (the first one after the last
// the outbox kept), kept in the outbox before the Will names it, so that a
// restart (a power cut included) never reuses the bdSeq of a session whose
// death certificate a host may still receive. The count in memory decides:
// a value the outbox could not keep is never handed out twice in this run.
void MqttNode::take_bd_seq(bool first) {
  std::uint64_t next = (bd_seq_.load() + 1) % 256;
  if (first) {
    next = 0;
    if (outbox_) {
      if (auto last = outbox_->last_bd_seq(); !last)
        spdlog::warn("mqtt: the last bdSeq could not be read from {} ({}); starting at 0", outbox_->path(),
                     last.error().message);
      else if (*last)
        next = (**last + 1) % 256;
    }
  }
  bd_seq_ = next;
  if (outbox_)
    if (auto kept = outbox_->keep_bd_seq(next); !kept)
      spdlog::warn("mqtt: bdSeq {} could not be kept in {} ({}): a restart may register it again", next,
                   outbox_->path(), kept.error().message);
}

void MqttNode::start() {
  take_bd_seq(true);
  set_will();
  started_ = true;
  network_ = std::thread([this] {
    name_this_thread("mqtt-net");
    network_loop();
  });
  publisher_ = std::thread([this] {
    name_this_thread("mqtt-publish");
    publish_loop();
  });
  spdlog::info("mqtt: Sparkplug B edge node {} on {}://{}:{}{}", topic("NBIRTH"), config_.tls ? "mqtts" : "mqtt",
               config_.host, config_.port, config_.user.empty() ? "" : " as user " + config_.user);
}

// Our own network thread rather than libmosquitto's loop_start: that one
// never retries once its first connection fails, nor after a TLS error, and a
// module must reach a broker that comes back whatever went wrong before.
// Retries back off from 1 s to 30 s.
void MqttNode::network_loop() {
  int delay_s = 1;
  bool have_socket = false;
  const auto wait = [&] {
    for (int i = 0; i < delay_s * 10 && !stop_network_; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    delay_s = std::min(delay_s * 2, 30);
  };
  while (!stop_network_) {
    if (!have_socket) {
      // Asynchronous: a broker host that drops the SYN leaves the connect
      // pending in mosquitto_loop below, which returns every 100 ms, so a stop
      // never waits for the kernel's connect timeout (about 2 minutes).
      const int rc = mosquitto_connect_async(mosq_, config_.host.c_str(), config_.port, config_.keepalive_s);
      if (rc != MOSQ_ERR_SUCCESS && rc != MOSQ_ERR_CONN_PENDING) {
        log_once(fmt::format("cannot connect: {}; retrying",
                             rc == MOSQ_ERR_ERRNO ? std::string(std::strerror(errno)) : mosquitto_strerror(rc)));
        wait();
        continue;
      }
      have_socket = true;
    }
    const int rc = mosquitto_loop(mosq_, 100, 1);
    if (rc != MOSQ_ERR_SUCCESS) {
      have_socket = false;
      if (connected_.exchange(false)) on_session_lost(rc);
      else
        log_once(fmt::format("no MQTT session: {} before the broker accepted the connection (is it an MQTT "
                             "listener? mqtts:// for a TLS port); retrying",
                             rc == MOSQ_ERR_ERRNO ? std::string(std::strerror(errno)) : mosquitto_strerror(rc)));
      wait();
    } else if (connected_) {
      delay_s = 1;
    }
  }
}

void MqttNode::log_once(const std::string& text) {
  std::lock_guard lock(log_mutex_);
  // Once per reason until a session is made: a refused connection reports
  // two (the broker's answer, then the closed socket), alternating each retry.
  if (logged_reasons_.size() >= 64) logged_reasons_.clear();  // texts with varying figures stay bounded
  if (!logged_reasons_.insert(text).second) return;
  spdlog::warn("mqtt: {}:{}: {}", config_.host, config_.port, text);
}

void MqttNode::stop() {
  if (!started_) return;
  started_ = false;
  stop_ = true;
  if (publisher_.joinable()) publisher_.join();
  stop_network_ = true;
  if (network_.joinable()) network_.join();
  {
    std::lock_guard lock(ncmd_log_mutex_);
    ncmd_log_.flush_all(RefusalLog::Clock::now());
  }
  // Alone on the client now: the death certificate, written out, then goodbye.
  if (connected_) {
    const std::string bytes = sparkplug::EdgeNode::death(bd_seq_.load()).SerializeAsString();
    int mid = 0;
    mosquitto_publish(mosq_, &mid, topic("NDEATH").c_str(), static_cast<int>(bytes.size()), bytes.data(), 1, false);
    for (int i = 0; i < 20 && mosquitto_want_write(mosq_); ++i) mosquitto_loop(mosq_, 50, 1);
  }
  mosquitto_disconnect(mosq_);
  mosquitto_loop(mosq_, 50, 1);
}

void MqttNode::on_connect(mosquitto* m, void* self_ptr, int rc) {
  auto* self = static_cast<MqttNode*>(self_ptr);
  if (rc != 0) {
    self->log_once(std::string("broker refused the connection: ") + mosquitto_connack_string(rc));
    return;
  }
  mosquitto_subscribe(m, nullptr, self->topic("NCMD").c_str(), 1);
  if (!self->config_.primary_host.empty()) {
    {
      std::lock_guard lock(self->host_mutex_);
      self->host_.forget();
    }
    mosquitto_subscribe(m, nullptr, sparkplug::state_topic(self->config_.primary_host).c_str(), 1);
  }
  self->connected_ = true;
  self->need_birth_ = true;
  {
    std::lock_guard lock(self->log_mutex_);
    self->logged_reasons_.clear();
  }
  spdlog::info("mqtt: connected to {}:{} (bdSeq {})", self->config_.host, self->config_.port, self->bd_seq_.load());
}

// The next session gets the next bdSeq, and its Will says so before the
// reconnect registers it (take_bd_seq). What was in flight may not have arrived: sent again
// after the next birth.
void MqttNode::on_session_lost(int rc) {
  {
    std::lock_guard lock(flight_mutex_);
    in_flight_.clear();
    resend_all_ = true;
  }
  // A clean stop ends the last session: no next one takes a bdSeq.
  if (!stop_network_) {
    take_bd_seq(false);
    set_will();
  }
  if (rc != MOSQ_ERR_SUCCESS) spdlog::warn("mqtt: lost the broker ({}); reconnecting", mosquitto_strerror(rc));
}

void MqttNode::on_disconnect(mosquitto*, void* self_ptr, int rc) {
  auto* self = static_cast<MqttNode*>(self_ptr);
  if (self->connected_.exchange(false)) self->on_session_lost(rc);
}

// libmosquitto's own errors (a TLS handshake the broker refused, a
// certificate that does not verify): the why of a connection that fails. A
// line repeated on each reconnect attempt is logged once until another one.
void MqttNode::on_log(mosquitto*, void* self_ptr, int level, const char* text) {
  if (!(level & (MOSQ_LOG_ERR | MOSQ_LOG_WARNING)) || !text) return;
  static_cast<MqttNode*>(self_ptr)->log_once(text);
}

// The primary host's STATE: online lets the node be born; offline after the
// birth ends the session (NDEATH, disconnect), and the node waits in a new
// one, as Sparkplug 3.0 asks of an edge node with a primary host.
void MqttNode::take_host_state(const mosquitto_message* msg) {
  const auto state = sparkplug::parse_host_state(
      std::string_view(static_cast<const char*>(msg->payload), static_cast<std::size_t>(msg->payloadlen)));
  if (!state) {
    spdlog::warn("mqtt: {} is not a STATE message ({{\"online\": bool, \"timestamp\": ms}}); ignored", msg->topic);
    return;
  }
  std::lock_guard lock(host_mutex_);
  if (!host_.take(*state)) return;
  spdlog::info("mqtt: primary host {} is {}", config_.primary_host, state->online ? "online" : "offline");
  if (state->online) need_birth_ = true;
  else host_gone_ = true;
}

// An NCMD command: a momentary command coil of the module (cmd/home_all,
// cmd/home/x, cmd/abort, cmd/reset_alarm, ...) written through the same path
// as a Modbus write, so the same interlocks and refusals. Held commands (jog,
// the homing permit) are not taken: a broker's latency must not keep an axis
// moving. Every command is answered as an event (kind command): accepted, or
// the refusal with its reason.
// How the control loop judged the commands so far: status.command_count and
// status.last_command_result, read as a Modbus client reads them.
std::pair<std::int64_t, std::int64_t> MqttNode::judged() {
  static const registers::Register* count = registers::find_register("status.command_count");
  static const registers::Register* result = registers::find_register("status.last_command_result");
  std::pair<std::int64_t, std::int64_t> out{0, 0};
  service_.with_module_view([&](const registers::ModuleView& v) {
    out = {registers::read_raw(*count, v), registers::read_raw(*result, v)};
  });
  return out;
}

void MqttNode::take_command(const std::string& metric, bool on) {
  std::string name = metric;
  std::ranges::replace(name, '/', '.');
  // event/code: the command result (status.last_command_result, 0 = never
  // judged); event/new_value: the refusal reason of the write (status.last_refusal_reason, 0 = none).
  persistence::Event answer{.time_ms = now_ms(), .kind = persistence::EventKind::command, .name = name, .text = {}};
  const registers::Register* reg = registers::find_register(name);
  const bool momentary = reg && reg->unit == registers::Unit::module && reg->table == registers::Table::coil &&
                         reg->access == registers::Access::w;
  if (!config_.commands) {
    answer.new_value = static_cast<std::int64_t>(registers::RefusalReason::client_read_only);
    answer.text = fmt::format("NCMD {} refused: commands over MQTT are off (homingd --mqtt-commands turns them on)", metric);
  } else if (!momentary) {
    answer.new_value = static_cast<std::int64_t>(registers::RefusalReason::not_mapped);
    answer.text = fmt::format("NCMD {} refused: not a command of this module over MQTT (the momentary cmd.* coils only: "
                              "home, abort, reset, unhome, move, lock settings; no jog, no settings)", metric);
  } else if (!on) {
    answer.new_value = static_cast<std::int64_t>(registers::RefusalReason::out_of_range);
    answer.text = fmt::format("NCMD {} refused: a command is carried out by writing true", metric);
  } else {
    const ClientInfo client(0, Transport::mqtt, config_.host + ":" + std::to_string(config_.port));
    const auto before = judged();
    if (const auto refusal = service_.command(*reg, true, client)) {
      answer.new_value = refusal->reason_code();
      answer.text = fmt::format("NCMD {} refused: {} ({}): {}", metric, homing::name_of(refusal->reason),
                                registers::exception_name(refusal->code), refusal->message);
    } else if (reg->key == registers::Key::cmd_lock_settings) {
      // Carried out by the service itself: the loop never judges it, so
      // waiting for a judgement would hold this network thread for nothing.
      answer.code = static_cast<std::int32_t>(homing::CommandResult::accepted);
      answer.text = fmt::format("NCMD {}: settings locked", metric);
    } else {
      // The loop judges a command within a period or two; the network thread
      // may wait that long (the control loop never waits for it).
      auto now = before;
      for (int i = 0; i < 2000 && now.first == before.first; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        now = judged();
      }
      if (now.first != before.first) {
        const auto result = static_cast<homing::CommandResult>(now.second);
        answer.code = static_cast<std::int32_t>(now.second);
        answer.text = fmt::format("NCMD {}: {}: {}", metric, homing::command_result_name(result),
                                  homing::text_of(result));
      } else {
        answer.text = fmt::format("NCMD {} taken; the control loop did not judge it within 2 s: see status/last_command_result", metric);
      }
    }
  }
  // One reason per command and outcome: a host repeating a refused command
  // gets its first line whole, then counts.
  if (answer.new_value != 0 || (answer.code > 1))
    ncmd_refused(answer.new_value != 0
                     ? fmt::format("{} refused (reason {})", metric, answer.new_value)
                     : fmt::format("{} {}", metric,
                                   homing::command_result_name(static_cast<homing::CommandResult>(answer.code))),
                 "mqtt: " + answer.text);
  if (!outbox_) return;
  if (auto r = outbox_->push(std::move(answer)); !r)
    spdlog::error("mqtt: the answer to an NCMD could not be kept ({}): {}", outbox_->path(), r.error().message);
}

void MqttNode::ncmd_refused(const std::string& reason, const std::string& line) {
  std::lock_guard lock(ncmd_log_mutex_);
  ncmd_log_.refused(topic("NCMD"), reason, spdlog::level::warn, line, RefusalLog::Clock::now());
}

bool MqttNode::may_publish() {
  if (!connected_) return false;
  if (config_.primary_host.empty()) return true;
  std::lock_guard lock(host_mutex_);
  return host_.online();
}

void MqttNode::on_message(mosquitto*, void* self_ptr, const mosquitto_message* msg) {
  auto* self = static_cast<MqttNode*>(self_ptr);
  if (!self->config_.primary_host.empty() && sparkplug::state_topic(self->config_.primary_host) == msg->topic) {
    self->take_host_state(msg);
    return;
  }
  // Sparkplug B: an NCMD is never retained. A retained one is an old message
  // the broker replays at every subscription, that is at every start and
  // reconnection: carried out, it would home or move the machine each time.
  if (msg->retain) {
    self->ncmd_refused("retained", fmt::format("mqtt: NCMD on {} ignored: it is retained on the broker (an old command "
                                               "replayed at this subscription; Sparkplug B NCMDs are published with "
                                               "retain false); clear it with an empty retained message on that topic",
                                               msg->topic));
    return;
  }
  sparkplug::Payload cmd;
  if (!cmd.ParseFromArray(msg->payload, msg->payloadlen)) {
    self->ncmd_refused("not a Sparkplug B payload",
                       fmt::format("mqtt: NCMD on {} is not a Sparkplug B payload; ignored", msg->topic));
    return;
  }
  for (const auto& metric : cmd.metrics()) {
    if (metric.name() == sparkplug::kRebirthName && metric.boolean_value()) {
      spdlog::info("mqtt: rebirth requested");
      self->need_birth_ = true;
    } else if (metric.name().starts_with("cmd/") && metric.datatype() == static_cast<std::uint32_t>(sparkplug::DataType::boolean)) {
      self->take_command(metric.name(), metric.boolean_value());
    } else {
      self->ncmd_refused("a metric not taken",
                         fmt::format("mqtt: NCMD metric '{}' ignored: only Node Control/Rebirth and Boolean cmd/... "
                                     "metrics are taken",
                                     metric.name()));
    }
  }
}

bool MqttNode::publish(std::string_view type, const std::string& bytes) {
  const int rc = mosquitto_publish(mosq_, nullptr, topic(type).c_str(), static_cast<int>(bytes.size()),
                                   bytes.data(), 0, false);
  return rc == MOSQ_ERR_SUCCESS;
}

// An event leaves the outbox once libmosquitto has written it to the broker's
// connection (NDATA is QoS 0 by the specification: that is the last word the
// node gets); until then a lost connection sends it again after the next birth.
void MqttNode::on_publish(mosquitto*, void* self_ptr, int mid) {
  auto* self = static_cast<MqttNode*>(self_ptr);
  std::int64_t id = 0;
  {
    std::lock_guard lock(self->flight_mutex_);
    auto it = self->in_flight_.find(mid);
    if (it == self->in_flight_.end()) return;
    id = it->second;
    self->in_flight_.erase(self->in_flight_.begin(), std::next(it));
  }
  if (auto r = self->outbox_->remove_through(id); !r)
    spdlog::error("mqtt: delivered events not removed from {}: {}", self->outbox_->path(), r.error().message);
}

// The outbox's events after those already handed over in this session, oldest
// first, each as its own NDATA.
void MqttNode::send_events(sparkplug::EdgeNode& node) {
  if (!outbox_) return;
  auto events = outbox_->oldest(64, sent_through_);
  if (!events) {
    spdlog::error("mqtt: events not read from {}: {}", outbox_->path(), events.error().message);
    return;
  }
  if (events->empty()) return;
  const std::int64_t dropped = outbox_->dropped();
  for (const auto& e : *events) {
    auto payload = node.event(e, static_cast<std::uint64_t>(e.time_ms) < birth_ms_, dropped,
                              static_cast<std::uint64_t>(now_ms()));
    if (!payload) return;
    const std::string bytes = payload->SerializeAsString();
    int mid = 0;
    std::lock_guard lock(flight_mutex_);  // on_publish may come before mosquitto_publish returns
    if (mosquitto_publish(mosq_, &mid, topic("NDATA").c_str(), static_cast<int>(bytes.size()), bytes.data(), 0,
                          false) != MOSQ_ERR_SUCCESS) {
      need_birth_ = true;
      return;
    }
    in_flight_[mid] = e.id;
    sent_through_ = e.id;
  }
}

void MqttNode::publish_loop() {
  sparkplug::EdgeNode node(config_.report);
  while (!stop_) {
    if (host_gone_.exchange(false) && connected_) {
      const std::string bytes = sparkplug::EdgeNode::death(bd_seq_.load()).SerializeAsString();
      mosquitto_publish(mosq_, nullptr, topic("NDEATH").c_str(), static_cast<int>(bytes.size()), bytes.data(), 1, false);
      mosquitto_disconnect(mosq_);  // the network thread connects again, with the next bdSeq
    }
    if (may_publish()) {
      service_.with_module_view([&](const registers::ModuleView& view) {
        const sparkplug::ModuleReader read{
            [&](const registers::Register& reg) { return registers::read_raw(reg, view); },
            [&](const registers::Register& code) { return sparkplug::alarm_text(code, view); }};
        if (need_birth_.exchange(false)) {
          const auto now = static_cast<std::uint64_t>(now_ms());
          const std::int64_t dropped = outbox_ ? outbox_->dropped() : 0;
          if (!publish("NBIRTH", node.birth(bd_seq_.load(), read, now, dropped).SerializeAsString())) {
            need_birth_ = true;  // not connected after all: born again on the next connection
          } else {
            birth_ms_ = now;
            if (resend_all_.exchange(false)) sent_through_ = 0;  // a new session: all the outbox holds is owed
          }
        } else if (auto data = node.data(read, static_cast<std::uint64_t>(now_ms()))) {
          if (!publish("NDATA", data->SerializeAsString())) need_birth_ = true;
        }
      });
      if (!need_birth_) send_events(node);
    }
    {
      std::lock_guard lock(ncmd_log_mutex_);
      ncmd_log_.flush(RefusalLog::Clock::now());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(config_.sample_ms));
  }
}

}  // namespace server
