#pragma once
// The plant events a module owes its MQTT broker (homing cycles, alarms,
// settings changes), kept durably in their own small SQLite file until they
// are handed to the broker: a broker that is away, or a power cut while it
// is, loses none of them. Bounded: past max_events the oldest are dropped and
// counted, so a broker away for months cannot fill the disk.
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "persistence/error.hpp"

namespace persistence {

enum class EventKind : std::int32_t {
  cycle_started = 1,
  cycle_ended = 2,
  alarm_raised = 3,
  alarms_reset = 4,
  setting_changed = 5,
  command = 6,  // a command over MQTT (NCMD): code 0 = accepted, else the refusal reason (status.last_refusal_reason)
};
std::string_view event_kind_name(EventKind kind);

struct Event {
  std::int64_t id = 0;       // assigned by push: increasing, never reused
  std::int64_t time_ms = 0;  // when it happened (Unix ms)
  EventKind kind = EventKind::cycle_started;
  std::int32_t axis = -1;    // 0 = X ... 5 = C; -1 the machine
  std::int32_t code = 0;     // alarm code; a cycle's result (0 = homed, else its alarm)
  std::int64_t duration_ms = 0;  // cycle_ended
  std::int32_t axes = 0;     // a cycle's axes, bit 0 = X
  std::string name{};        // setting_changed: the register name
  std::int64_t old_value = 0, new_value = 0;  // setting_changed: raw register values
  std::string text{};        // what a technician reads
};

class EventOutbox {
 public:
  static Result<EventOutbox> open(const std::string& path, std::size_t max_events);
  EventOutbox(EventOutbox&&) noexcept;
  EventOutbox& operator=(EventOutbox&&) = delete;
  ~EventOutbox();

  // Durable once it returns (committed); the event's id. A settings change
  // read from the settings audit log also moves the audit cursor in the same
  // commit, so a change is neither lost nor sent twice across a power cut.
  Result<std::int64_t> push(Event event, std::optional<std::int64_t> audit_id = std::nullopt);
  // The last settings audit row turned into an event; none in a new outbox.
  std::optional<std::int64_t> audit_cursor() const;
  Status set_audit_cursor(std::int64_t audit_id);
  // The Sparkplug bdSeq of the last MQTT session the node registered (none
  // in a new outbox), kept so that a restart goes on from it and never
  // registers again the bdSeq of a session a host may still hold a death
  // certificate for. keep_bd_seq is durable once it returns.
  Result<std::optional<std::uint64_t>> last_bd_seq() const;
  Status keep_bd_seq(std::uint64_t bd_seq);
  // The oldest events still owed after this id, oldest first, at most n.
  Result<std::vector<Event>> oldest(std::size_t n, std::int64_t after_id = 0) const;
  // Events up to and including this id are delivered.
  Status remove_through(std::int64_t id);
  // How many events the bound has dropped since this file was made.
  std::int64_t dropped() const;
  std::size_t size() const;
  const std::string& path() const;

 private:
  struct Impl;
  explicit EventOutbox(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace persistence
