#pragma once
// Edit sessions: settings an HMI writes one tag at a time, applied together
// (docs/hmi-integration.md "Edit sessions"). A client begins a session
// (edit.command = 1); its settings writes are then range-checked and staged,
// not applied; its commit (2) checks the combination rules over the whole
// staged set and applies all of it in one transaction or none; discard (3)
// drops it. A session left longer than global.edit_timeout_s without a write
// or a commit is discarded and becomes expired: that client's settings writes
// are refused until it begins again or discards, so an HMI that believes it
// stages never applies tags one by one unawares.
//
// A session belongs to its connection (TCP, TLS: address and port; RTU: the
// serial line), as a database transaction does: a connection that closes
// discards its session. Pure: the caller passes the time and holds the lock.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "registers/validate.hpp"
#include "request_handler.hpp"

namespace server {

enum class EditState : std::uint8_t { none = 0, open = 1, expired = 2 };

class EditSessions {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::size_t kMaxSessions = 32;

  // Who a session belongs to (see above).
  static std::string owner_of(const ClientInfo& client);

  EditState state(const std::string& owner) const;
  std::size_t staged_count(const std::string& owner) const;

  enum class Begun { begun, already_open, full };
  Begun begin(const std::string& owner, Clock::time_point now);
  // Stages decoded settings writes into the owner's open session (a later
  // value of a register replaces an earlier one).
  void stage(const std::string& owner, std::span<const registers::RawWrite> writes, Clock::time_point now);
  // The staged writes, in address order (validate_raw_writes takes them so).
  std::vector<registers::RawWrite> staged(const std::string& owner) const;
  // Ends the owner's session or forgets its expiry (commit done, discard).
  void close(const std::string& owner);
  // A refused commit keeps the session: its clock restarts.
  void touch(const std::string& owner, Clock::time_point now);

  struct Expired {
    std::string owner;
    std::size_t staged = 0;
  };
  // Open sessions idle longer than `timeout` are discarded and become expired.
  std::vector<Expired> expire(Clock::time_point now, std::chrono::seconds timeout);
  std::size_t open_count() const;
  // No session open or expired: every owner's state is none.
  bool empty() const { return sessions_.empty(); }

 private:
  struct Session {
    EditState state = EditState::open;
    Clock::time_point last{};
    std::map<std::uint16_t, registers::RawWrite> staged;  // by address
  };
  std::map<std::string, Session> sessions_;
};

}  // namespace server
