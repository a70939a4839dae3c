#pragma once
// The primary host application's STATE message (Sparkplug 3.0):
// spBv1.0/STATE/<host id>, retained, a UTF-8 JSON object
// {"online": true|false, "timestamp": <ms>}. An edge node configured with a
// primary host publishes only while that host says it is online.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace sparkplug {

struct HostState {
  bool online = false;
  std::uint64_t timestamp = 0;
};

std::string state_topic(std::string_view host_id);
// nullopt: not a STATE payload (not JSON, no boolean "online", no integer "timestamp").
std::optional<HostState> parse_host_state(std::string_view payload);

// What the edge node makes of a sequence of STATE messages: an older
// timestamp than the last one taken is stale (a retained message overtaken
// by a newer one) and changes nothing.
class PrimaryHost {
 public:
  // true when the state changed.
  bool take(const HostState& s);
  bool online() const { return online_; }
  void forget() { online_ = false; }  // a new MQTT session: wait for the host again

 private:
  bool online_ = false;
  std::uint64_t timestamp_ = 0;
};

}  // namespace sparkplug
