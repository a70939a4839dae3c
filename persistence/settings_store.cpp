// SettingsStore: the settings (load, commit with the audit row), the
// "settings lost" latch, limits, close. Opening is store_open.cpp, backups
// store_backup.cpp, the history store_history.cpp, export/import transfer.cpp.
#include "persistence/settings_store.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "persistence/store_impl.hpp"

namespace persistence {

std::string_view outcome_name(OpenOutcome o) {
  switch (o) {
    case OpenOutcome::created: return "created";
    case OpenOutcome::opened: return "opened";
    case OpenOutcome::restored_from_backup: return "restored_from_backup";
    case OpenOutcome::defaults_settings_lost: return "defaults_settings_lost";
  }
  return "?";
}

std::int64_t SettingsStore::Impl::now_ms() const {
  if (opt.now_ms) return opt.now_ms();
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

SettingsStore::SettingsStore(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SettingsStore::SettingsStore(SettingsStore&&) noexcept = default;
SettingsStore& SettingsStore::operator=(SettingsStore&& other) noexcept {
  if (this != &other) {
    close();
    impl_ = std::move(other.impl_);
  }
  return *this;
}
SettingsStore::~SettingsStore() { close(); }

void SettingsStore::close() {
  if (!impl_) return;
  std::lock_guard lock(impl_->mu);
  if (!impl_->db) return;
  if (impl_->backup_dirty && !impl_->opt.read_only) {
    if (auto s = impl_->backup_locked(); !s) impl_->log->warn("{}", s.error().message);
  }
  impl_->update_stmt.reset();  // statements of this connection go before it
  impl_->audit_stmt.reset();
  {
    // Before the writer's: the last connection to close checkpoints the WAL and removes it.
    std::lock_guard house_lock(impl_->house_mu);
    impl_->house.reset();
    impl_->house_closed = true;
  }
  impl_->db.close();
}

const std::string& SettingsStore::path() const { return impl_->path; }

std::map<std::string, std::int64_t> SettingsStore::load() const {
  std::lock_guard lock(impl_->mu);
  return impl_->values;
}

std::optional<std::int64_t> SettingsStore::value(const std::string& name) const {
  std::lock_guard lock(impl_->mu);
  auto it = impl_->values.find(name);
  if (it == impl_->values.end()) return std::nullopt;
  return it->second;
}

Result<std::vector<Change>> SettingsStore::commit(const std::vector<SettingWrite>& writes, const ChangeSource& source) {
  auto changes = commit_batch({BatchEntry{&writes, source}});
  if (!changes) return std::unexpected(changes.error());
  return std::move(changes->front());
}

Result<std::vector<std::vector<Change>>> SettingsStore::commit_batch(const std::vector<BatchEntry>& entries) {
  std::lock_guard lock(impl_->mu);
  auto changes = impl_->commit_locked(entries);
  if (!changes) {
    changes.error().message += "; nothing was written, the old settings stay in force";
    return changes;
  }
  const bool any = std::any_of(changes->begin(), changes->end(), [](const auto& c) { return !c.empty(); });
  if (any && impl_->opt.backup_on_commit) {
    if (auto s = impl_->backup_if_due_locked(); !s) impl_->log->warn("{}", s.error().message);
  }
  return changes;
}

Status SettingsStore::Impl::prepare_write_statements() {
  if (!update_stmt) {
    auto upd = db.prepare("UPDATE settings SET value = ? WHERE name = ?");
    if (!upd) return std::unexpected(upd.error());
    update_stmt.emplace(std::move(*upd));
  }
  if (!audit_stmt) {
    auto aud = db.prepare(
        "INSERT INTO audit(time_ms, transport, client, name, old_value, new_value) VALUES(?, ?, ?, ?, ?, ?)");
    if (!aud) return std::unexpected(aud.error());
    audit_stmt.emplace(std::move(*aud));
  }
  return {};
}

Result<std::vector<std::vector<Change>>> SettingsStore::Impl::commit_locked(const std::vector<BatchEntry>& entries) {
  if (!db) return fail(ErrorKind::internal, fmt::format("{}: commit on a closed settings store", path));
  if (opt.read_only)
    return fail(ErrorKind::read_only, fmt::format("{}: opened read-only; settings cannot be written", path));
  // The values this batch has written so far, over the committed ones (a
  // later write of the batch compares with an earlier one's value): a few
  // entries, where a copy of every value would cost each write a map.
  std::vector<std::pair<std::map<std::string, std::int64_t>::iterator, std::int64_t>> written;
  std::vector<std::vector<Change>> changes(entries.size());
  bool any = false;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    for (const auto& w : *entries[i].writes) {
      auto it = values.find(w.name);
      if (it == values.end())
        return fail(ErrorKind::invalid, fmt::format("{}: unknown register '{}'; nothing written", path, w.name));
      auto pending = std::find_if(written.begin(), written.end(), [&](const auto& p) { return p.first == it; });
      const std::int64_t current = pending == written.end() ? it->second : pending->second;
      if (current != w.value) {
        changes[i].push_back({w.name, current, w.value});
        if (pending == written.end()) written.emplace_back(it, w.value);
        else pending->second = w.value;
        any = true;
      }
    }
  }
  if (!any) return changes;  // already durable

  const std::int64_t t = now_ms();
  if (auto s = prepare_write_statements(); !s) return std::unexpected(s.error());
  auto txn = sql::Transaction::begin(db, "starting a settings write");
  if (!txn) return std::unexpected(txn.error());
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const ChangeSource& source = entries[i].source;
    for (const auto& c : changes[i]) {
      update_stmt->bind(1, c.new_value).bind(2, std::string_view(c.name));
      if (auto s = update_stmt->run(fmt::format("writing setting '{}'", c.name)); !s) return std::unexpected(s.error());
      audit_stmt->bind(1, t)
          .bind(2, std::string_view(source.transport))
          .bind(3, std::string_view(source.client))
          .bind(4, std::string_view(c.name))
          .bind(5, c.old_value)
          .bind(6, c.new_value);
      if (auto s = audit_stmt->run("writing the audit log"); !s) return std::unexpected(s.error());
    }
  }
  if (auto s = txn->commit("committing a settings write"); !s) return std::unexpected(s.error());
  for (const auto& [it, value] : written) it->second = value;
  backup_dirty = true;
  return changes;
}

Status SettingsStore::prune_audit() {
  std::lock_guard lock(impl_->mu);
  auto& m = *impl_;
  if (!m.db || m.opt.read_only) return {};
  if (sqlite3_total_changes64(m.db.get()) == m.pruned_at_changes) return {};  // no row added since
  auto prune = m.db.prepare("DELETE FROM audit WHERE id <= (SELECT max(id) FROM audit) - ?");
  if (!prune) return std::unexpected(prune.error());
  prune->bind(1, static_cast<std::int64_t>(std::max<std::size_t>(m.opt.audit_max_rows, 1)));
  if (auto s = prune->run("pruning the audit log"); !s) return s;
  m.pruned_at_changes = sqlite3_total_changes64(m.db.get());
  return {};
}

bool SettingsStore::settings_lost() const { return impl_->settings_lost.load(); }

Status SettingsStore::acknowledge_settings_lost(const ChangeSource& source) {
  std::lock_guard lock(impl_->mu);
  auto& m = *impl_;
  if (!m.settings_lost) return {};
  auto txn = sql::Transaction::begin(m.db, "starting to clear the settings-lost flag");
  if (!txn) return std::unexpected(txn.error());
  {
    auto del = m.db.prepare("DELETE FROM meta WHERE key = ?");
    if (!del) return std::unexpected(del.error());
    del->bind(1, kLostKey);
    if (auto s = del->run("clearing the settings-lost flag"); !s) return s;
    auto aud = m.db.prepare(
        "INSERT INTO audit(time_ms, transport, client, name, old_value, new_value) VALUES(?, ?, ?, ?, 1, 0)");
    if (!aud) return std::unexpected(aud.error());
    aud->bind(1, m.now_ms())
        .bind(2, std::string_view(source.transport))
        .bind(3, std::string_view(source.client))
        .bind(4, kLostKey);
    if (auto s = aud->run("writing the audit log"); !s) return s;
  }
  if (auto s = txn->commit("committing the settings-lost acknowledgement"); !s) return s;
  m.settings_lost = false;
  m.backup_dirty = true;
  m.log->warn("settings database {}: 'settings lost' acknowledged by {} {}", m.path, source.transport, source.client);
  return {};
}

Status SettingsStore::audit(const Change& change, const ChangeSource& source) {
  std::lock_guard lock(impl_->mu);
  auto& m = *impl_;
  auto txn = sql::Transaction::begin(m.db, "starting an audit row");
  if (!txn) return std::unexpected(txn.error());
  {
    auto aud = m.db.prepare(
        "INSERT INTO audit(time_ms, transport, client, name, old_value, new_value) VALUES(?, ?, ?, ?, ?, ?)");
    if (!aud) return std::unexpected(aud.error());
    aud->bind(1, m.now_ms())
        .bind(2, std::string_view(source.transport))
        .bind(3, std::string_view(source.client))
        .bind(4, std::string_view(change.name))
        .bind(5, change.old_value)
        .bind(6, change.new_value);
    if (auto s = aud->run(fmt::format("writing the audit row of '{}'", change.name)); !s) return s;
    auto prune = m.db.prepare("DELETE FROM audit WHERE id <= (SELECT max(id) FROM audit) - ?");
    if (!prune) return std::unexpected(prune.error());
    prune->bind(1, static_cast<std::int64_t>(std::max<std::size_t>(m.opt.audit_max_rows, 1)));
    if (auto s = prune->run("pruning the audit log"); !s) return s;
  }
  return txn->commit("committing an audit row");
}

Status SettingsStore::set_limits(std::size_t audit_max_rows, std::size_t history_max_rows) {
  std::lock_guard lock(impl_->mu);
  impl_->opt.audit_max_rows = std::max<std::size_t>(audit_max_rows, 1);
  impl_->opt.history_max_rows = std::max<std::size_t>(history_max_rows, 1);
  impl_->pruned_at_changes = -1;  // a lower bound prunes at the next look
  return {};
}

Status SettingsStore::check_integrity() const {
  std::lock_guard lock(impl_->mu);
  auto p = impl_->db.integrity_problems();
  if (!p) return std::unexpected(p.error());
  if (*p) return fail(ErrorKind::corrupt, fmt::format("{}: integrity check failed: {}", impl_->path, **p));
  return {};
}

Result<DurabilitySettings> SettingsStore::durability() const {
  std::lock_guard lock(impl_->mu);
  const auto& db = impl_->db;
  if (!db) return fail(ErrorKind::internal, fmt::format("{}: durability of a closed settings store", impl_->path));
  DurabilitySettings d;
  auto mode = db.prepare("PRAGMA journal_mode");
  if (!mode) return std::unexpected(mode.error());
  auto row = mode->step("reading the journal mode");
  if (!row) return std::unexpected(row.error());
  if (*row) d.journal_mode = mode->text_at(0);
  auto sync = db.query_int("PRAGMA synchronous", "reading the synchronous level");
  if (!sync) return std::unexpected(sync.error());
  d.synchronous = static_cast<int>(*sync);
  return d;
}

}  // namespace persistence
