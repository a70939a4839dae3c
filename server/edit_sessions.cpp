#include "edit_sessions.hpp"

#include <algorithm>

namespace server {

std::string EditSessions::owner_of(const ClientInfo& client) {
  std::string owner = std::string(transport_name(client.transport)) + " " + client.address;
  if (!client.identity.empty()) owner += " " + client.identity;
  return owner;
}

EditState EditSessions::state(const std::string& owner) const {
  const auto it = sessions_.find(owner);
  return it == sessions_.end() ? EditState::none : it->second.state;
}

std::size_t EditSessions::staged_count(const std::string& owner) const {
  const auto it = sessions_.find(owner);
  return it == sessions_.end() || it->second.state != EditState::open ? 0 : it->second.staged.size();
}

EditSessions::Begun EditSessions::begin(const std::string& owner, Clock::time_point now) {
  const auto it = sessions_.find(owner);
  if (it != sessions_.end() && it->second.state == EditState::open) return Begun::already_open;
  if (it == sessions_.end() && open_count() >= kMaxSessions) return Begun::full;
  // Expired sessions are kept to refuse their owners' writes; many owners
  // that never came back give way, the longest gone first.
  while (it == sessions_.end() && sessions_.size() >= 4 * kMaxSessions) {
    auto oldest = sessions_.end();
    for (auto s = sessions_.begin(); s != sessions_.end(); ++s)
      if (s->second.state == EditState::expired && (oldest == sessions_.end() || s->second.last < oldest->second.last))
        oldest = s;
    if (oldest == sessions_.end()) break;
    sessions_.erase(oldest);
  }
  sessions_[owner] = Session{EditState::open, now, {}};
  return Begun::begun;
}

void EditSessions::stage(const std::string& owner, std::span<const registers::RawWrite> writes, Clock::time_point now) {
  const auto it = sessions_.find(owner);
  if (it == sessions_.end() || it->second.state != EditState::open) return;
  for (const registers::RawWrite& w : writes) it->second.staged[w.reg->address] = w;
  it->second.last = now;
}

std::vector<registers::RawWrite> EditSessions::staged(const std::string& owner) const {
  std::vector<registers::RawWrite> out;
  if (const auto it = sessions_.find(owner); it != sessions_.end())
    for (const auto& [address, w] : it->second.staged) out.push_back(w);
  return out;
}

void EditSessions::close(const std::string& owner) { sessions_.erase(owner); }

void EditSessions::touch(const std::string& owner, Clock::time_point now) {
  if (const auto it = sessions_.find(owner); it != sessions_.end()) it->second.last = now;
}

std::vector<EditSessions::Expired> EditSessions::expire(Clock::time_point now, std::chrono::seconds timeout) {
  std::vector<Expired> out;
  for (auto& [owner, s] : sessions_) {
    if (s.state != EditState::open || now - s.last <= timeout) continue;
    out.push_back({owner, s.staged.size()});
    s.state = EditState::expired;
    s.staged.clear();
  }
  return out;
}

std::size_t EditSessions::open_count() const {
  return static_cast<std::size_t>(
      std::count_if(sessions_.begin(), sessions_.end(), [](const auto& s) { return s.second.state == EditState::open; }));
}

}  // namespace server
