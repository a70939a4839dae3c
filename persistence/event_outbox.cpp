#include "persistence/event_outbox.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "persistence/sqlite_handle.hpp"

namespace persistence {
namespace {

constexpr std::string_view kSchema = R"sql(
CREATE TABLE IF NOT EXISTS events(
  id          INTEGER PRIMARY KEY AUTOINCREMENT,
  time_ms     INTEGER NOT NULL,
  kind        INTEGER NOT NULL,
  axis        INTEGER NOT NULL,
  code        INTEGER NOT NULL,
  duration_ms INTEGER NOT NULL,
  axes        INTEGER NOT NULL,
  name        TEXT NOT NULL,
  old_value   INTEGER NOT NULL,
  new_value   INTEGER NOT NULL,
  text        TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS counters(
  key   TEXT PRIMARY KEY NOT NULL,
  value INTEGER NOT NULL
) WITHOUT ROWID;
INSERT OR IGNORE INTO counters(key, value) VALUES('dropped', 0);
)sql";

}  // namespace

std::string_view event_kind_name(EventKind kind) {
  switch (kind) {
    case EventKind::cycle_started: return "cycle_started";
    case EventKind::cycle_ended: return "cycle_ended";
    case EventKind::alarm_raised: return "alarm_raised";
    case EventKind::alarms_reset: return "alarms_reset";
    case EventKind::setting_changed: return "setting_changed";
    case EventKind::command: return "command";
  }
  return "unknown";
}

struct EventOutbox::Impl {
  mutable std::mutex mutex;
  sql::Db db;
  std::size_t max_events = 0;
};

EventOutbox::EventOutbox(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
EventOutbox::EventOutbox(EventOutbox&&) noexcept = default;
EventOutbox::~EventOutbox() = default;

Result<EventOutbox> EventOutbox::open(const std::string& path, std::size_t max_events) {
  auto db = sql::Db::open(path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX);
  if (!db) return std::unexpected(db.error());
  // WAL with a full sync on every commit: an event pushed survives a power cut.
  if (auto s = db->exec("PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL;", "setting up the MQTT event outbox"); !s)
    return std::unexpected(s.error());
  if (auto s = db->exec(kSchema, "creating the MQTT event outbox"); !s) return std::unexpected(s.error());
  auto impl = std::make_unique<Impl>();
  impl->db = std::move(*db);
  impl->max_events = std::max<std::size_t>(max_events, 1);
  return EventOutbox(std::move(impl));
}

const std::string& EventOutbox::path() const { return impl_->db.path(); }

Result<std::int64_t> EventOutbox::push(Event e, std::optional<std::int64_t> audit_id) {
  std::lock_guard lock(impl_->mutex);
  sql::Db& db = impl_->db;
  auto txn = sql::Transaction::begin(db, "keeping an MQTT event");
  if (!txn) return std::unexpected(txn.error());
  auto ins = db.prepare(
      "INSERT INTO events(time_ms, kind, axis, code, duration_ms, axes, name, old_value, new_value, text) "
      "VALUES(?,?,?,?,?,?,?,?,?,?)");
  if (!ins) return std::unexpected(ins.error());
  ins->bind(1, e.time_ms).bind(2, std::int64_t{static_cast<std::int32_t>(e.kind)}).bind(3, std::int64_t{e.axis})
      .bind(4, std::int64_t{e.code}).bind(5, e.duration_ms).bind(6, std::int64_t{e.axes}).bind(7, e.name)
      .bind(8, e.old_value).bind(9, e.new_value).bind(10, e.text);
  if (auto s = ins->run("keeping an MQTT event"); !s) return std::unexpected(s.error());
  const std::int64_t id = sqlite3_last_insert_rowid(db.get());
  // Past the bound the oldest go, and are counted: a host sees the gap in the
  // ids and the count in event/dropped.
  auto count = db.query_int("SELECT count(*) FROM events", "counting MQTT events");
  if (!count) return std::unexpected(count.error());
  const auto over = *count - static_cast<std::int64_t>(impl_->max_events);
  if (over > 0) {
    if (auto s = db.exec(fmt::format("DELETE FROM events WHERE id IN (SELECT id FROM events ORDER BY id LIMIT {});"
                                     "UPDATE counters SET value = value + {} WHERE key = 'dropped';",
                                     over, over),
                         "dropping the oldest MQTT events beyond the bound");
        !s)
      return std::unexpected(s.error());
  }
  if (audit_id) {
    auto cur = db.prepare("INSERT OR REPLACE INTO counters(key, value) VALUES('audit_cursor', ?)");
    if (!cur) return std::unexpected(cur.error());
    cur->bind(1, *audit_id);
    if (auto s = cur->run("moving the audit cursor of the MQTT events"); !s) return std::unexpected(s.error());
  }
  if (auto s = txn->commit("keeping an MQTT event"); !s) return std::unexpected(s.error());
  return id;
}

std::optional<std::int64_t> EventOutbox::audit_cursor() const {
  std::lock_guard lock(impl_->mutex);
  auto q = impl_->db.prepare("SELECT value FROM counters WHERE key = 'audit_cursor'");
  if (!q) return std::nullopt;
  auto row = q->step("reading the audit cursor of the MQTT events");
  if (!row || !*row) return std::nullopt;
  return q->int_at(0);
}

Status EventOutbox::set_audit_cursor(std::int64_t audit_id) {
  std::lock_guard lock(impl_->mutex);
  auto cur = impl_->db.prepare("INSERT OR REPLACE INTO counters(key, value) VALUES('audit_cursor', ?)");
  if (!cur) return std::unexpected(cur.error());
  cur->bind(1, audit_id);
  return cur->run("setting the audit cursor of the MQTT events");
}

Result<std::optional<std::uint64_t>> EventOutbox::last_bd_seq() const {
  std::lock_guard lock(impl_->mutex);
  auto last = impl_->db.query_int("SELECT coalesce((SELECT value FROM counters WHERE key = 'bd_seq'), -1)",
                                  "reading the last Sparkplug bdSeq");
  if (!last) return std::unexpected(last.error());
  if (*last < 0 || *last > 255) return std::optional<std::uint64_t>{};  // none kept (or not one of ours)
  return std::optional<std::uint64_t>{static_cast<std::uint64_t>(*last)};
}

Status EventOutbox::keep_bd_seq(std::uint64_t bd_seq) {
  std::lock_guard lock(impl_->mutex);
  auto put = impl_->db.prepare("INSERT OR REPLACE INTO counters(key, value) VALUES('bd_seq', ?)");
  if (!put) return std::unexpected(put.error());
  put->bind(1, static_cast<std::int64_t>(bd_seq));
  return put->run("keeping the Sparkplug bdSeq");
}

Result<std::vector<Event>> EventOutbox::oldest(std::size_t n, std::int64_t after_id) const {
  std::lock_guard lock(impl_->mutex);
  auto q = impl_->db.prepare(
      "SELECT id, time_ms, kind, axis, code, duration_ms, axes, name, old_value, new_value, text FROM events "
      "WHERE id > ? ORDER BY id LIMIT ?");
  if (!q) return std::unexpected(q.error());
  q->bind(1, after_id).bind(2, static_cast<std::int64_t>(n));
  std::vector<Event> out;
  for (;;) {
    auto row = q->step("reading MQTT events");
    if (!row) return std::unexpected(row.error());
    if (!*row) break;
    Event e;
    e.id = q->int_at(0);
    e.time_ms = q->int_at(1);
    e.kind = static_cast<EventKind>(q->int_at(2));
    e.axis = static_cast<std::int32_t>(q->int_at(3));
    e.code = static_cast<std::int32_t>(q->int_at(4));
    e.duration_ms = q->int_at(5);
    e.axes = static_cast<std::int32_t>(q->int_at(6));
    e.name = q->text_at(7);
    e.old_value = q->int_at(8);
    e.new_value = q->int_at(9);
    e.text = q->text_at(10);
    out.push_back(std::move(e));
  }
  return out;
}

Status EventOutbox::remove_through(std::int64_t id) {
  std::lock_guard lock(impl_->mutex);
  auto del = impl_->db.prepare("DELETE FROM events WHERE id <= ?");
  if (!del) return std::unexpected(del.error());
  del->bind(1, id);
  return del->run("removing delivered MQTT events");
}

std::int64_t EventOutbox::dropped() const {
  std::lock_guard lock(impl_->mutex);
  auto v = impl_->db.query_int("SELECT value FROM counters WHERE key = 'dropped'", "reading the MQTT event count");
  return v ? *v : 0;
}

std::size_t EventOutbox::size() const {
  std::lock_guard lock(impl_->mutex);
  auto v = impl_->db.query_int("SELECT count(*) FROM events", "counting MQTT events");
  return v ? static_cast<std::size_t>(*v) : 0;
}

}  // namespace persistence
