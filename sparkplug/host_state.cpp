#include "sparkplug/host_state.hpp"

#include <nlohmann/json.hpp>

namespace sparkplug {

std::string state_topic(std::string_view host_id) { return "spBv1.0/STATE/" + std::string(host_id); }

std::optional<HostState> parse_host_state(std::string_view payload) {
  const auto j = nlohmann::json::parse(payload, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return std::nullopt;
  const auto online = j.find("online");
  const auto ts = j.find("timestamp");
  if (online == j.end() || !online->is_boolean()) return std::nullopt;
  if (ts == j.end() || !ts->is_number_integer() || ts->get<std::int64_t>() < 0) return std::nullopt;
  return HostState{online->get<bool>(), ts->get<std::uint64_t>()};
}

bool PrimaryHost::take(const HostState& s) {
  if (s.timestamp < timestamp_) return false;
  timestamp_ = s.timestamp;
  const bool changed = s.online != online_;
  online_ = s.online;
  return changed;
}

}  // namespace sparkplug
