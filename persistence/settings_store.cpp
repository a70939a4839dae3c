#include "persistence/settings_store.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>

#include "persistence/schema.hpp"
#include "persistence/store_impl.hpp"

namespace fs = std::filesystem;

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

namespace {

constexpr std::string_view kLostKey = "settings_lost";

std::string bak_path(const std::string& db, int generation) {
  return generation == 0 ? db + ".bak" : fmt::format("{}.bak.{}", db, generation);
}

bool exists(const std::string& p) {
  std::error_code ec;
  return fs::exists(p, ec);
}

void remove_quiet(const std::string& p) {
  std::error_code ec;
  fs::remove(p, ec);
}

Error os_error(const std::string& path, std::string_view what, int err) {
  ErrorKind kind = ErrorKind::io;
  if (err == EROFS || err == EACCES || err == EPERM) kind = ErrorKind::read_only;
  if (err == ENOSPC || err == EDQUOT || err == EFBIG) kind = ErrorKind::disk_full;
  return Error{kind, fmt::format("{}: {} failed: {}", path, what, std::strerror(err))};
}

Status fsync_path(const std::string& path, bool directory) {
  int fd = ::open(path.c_str(), (directory ? O_DIRECTORY : 0) | O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::unexpected(os_error(path, "opening for fsync", errno));
  int rc = ::fsync(fd);
  int err = errno;
  ::close(fd);
  if (rc != 0) return std::unexpected(os_error(path, "fsync", err));
  return {};
}

std::string dir_of(const std::string& path) {
  fs::path p = fs::absolute(fs::path(path)).parent_path();
  return p.empty() ? std::string(".") : p.string();
}

Status rename_durable(const std::string& from, const std::string& to) {
  if (::rename(from.c_str(), to.c_str()) != 0)
    return std::unexpected(os_error(from, fmt::format("renaming to {}", to), errno));
  return fsync_path(dir_of(to), true);
}

void remove_sidecars(const std::string& db) {
  remove_quiet(db + "-wal");
  remove_quiet(db + "-shm");
  remove_quiet(db + "-journal");
}

// Copies `from` to `to` through a temporary file, fsynced and renamed into place.
Status copy_durable(const std::string& from, const std::string& to) {
  std::string tmp = to + ".restore.tmp";
  std::error_code ec;
  fs::copy_file(from, tmp, fs::copy_options::overwrite_existing, ec);
  if (ec) return std::unexpected(os_error(tmp, fmt::format("copying {}", from), ec.value()));
  if (auto s = fsync_path(tmp, false); !s) return s;
  return rename_durable(tmp, to);
}

// Opens a database and configures durability: WAL + synchronous=FULL.
Result<sql::Db> open_configured(const std::string& path, bool create, const char* vfs) {
  int flags = SQLITE_OPEN_READWRITE | (create ? SQLITE_OPEN_CREATE : 0);
  auto db = sql::Db::open(path, flags, vfs);
  if (!db) return db;
  auto mode = db->prepare("PRAGMA journal_mode=WAL");
  if (!mode) return std::unexpected(mode.error());
  auto row = mode->step("switching to WAL journal mode");
  if (!row) return std::unexpected(row.error());
  if (!*row || mode->text_at(0) != "wal")
    return std::unexpected(Error{ErrorKind::io, fmt::format("{}: could not switch to WAL journal mode (got '{}'); "
                                                            "the file system may not support it",
                                                            path, *row ? mode->text_at(0) : "")});
  mode->reset();
  if (auto s = db->exec("PRAGMA synchronous=FULL", "setting synchronous=FULL"); !s) return std::unexpected(s.error());
  return db;
}

// Opens an existing database and proves it intact. Errors of kind `corrupt`
// mean "restore"; any other error is returned to the caller as is.
Result<sql::Db> open_verified(const std::string& path, const char* vfs, int& version) {
  auto db = open_configured(path, false, vfs);
  if (!db) return db;
  auto v = db->query_int("PRAGMA user_version", "reading the schema version");
  if (!v) return std::unexpected(v.error());
  version = static_cast<int>(*v);
  auto problems = db->integrity_problems();
  if (!problems) return std::unexpected(problems.error());
  if (*problems)
    return std::unexpected(Error{ErrorKind::corrupt, fmt::format("{}: integrity check failed: {}", path, **problems)});
  if (version > kSchemaVersion)
    return std::unexpected(Error{ErrorKind::version,
                                 fmt::format("{}: written by a newer firmware (schema version {}, this firmware "
                                             "knows up to {}); install that firmware or restore an exported "
                                             "settings file",
                                             path, version, kSchemaVersion)});
  return db;
}

// A backup is good if it opens read-only, passes the integrity check and has a
// schema this firmware can migrate.
std::optional<std::string> backup_problem(const std::string& file, const char* vfs) {
  auto db = sql::Db::open(file, SQLITE_OPEN_READONLY, vfs);
  if (!db) return db.error().message;
  auto v = db->query_int("PRAGMA user_version", "reading the schema version");
  if (!v) return v.error().message;
  if (*v < 1 || *v > kSchemaVersion) return fmt::format("{}: unusable schema version {}", file, *v);
  auto problems = db->integrity_problems();
  if (!problems) return problems.error().message;
  if (*problems) return fmt::format("{}: integrity check failed: {}", file, **problems);
  return std::nullopt;
}

Status migrate(sql::Db& db, int from, spdlog::logger& log) {
  const auto& steps = schema::steps();
  for (int v = from; v < kSchemaVersion; ++v) {
    const auto& step = steps.at(static_cast<std::size_t>(v));
    auto txn = sql::Transaction::begin(db, "starting a schema migration");
    if (!txn) return std::unexpected(txn.error());
    if (auto s = db.exec(step.sql, fmt::format("schema migration to v{} ({})", step.to_version, step.description)); !s)
      return s;
    if (auto s = db.exec(fmt::format("PRAGMA user_version = {}", step.to_version), "setting the schema version"); !s)
      return s;
    if (auto s = txn->commit("committing a schema migration"); !s) return s;
    if (from > 0) log.info("settings database {}: schema migrated to v{} ({})", db.path(), step.to_version, step.description);
  }
  return {};
}

}  // namespace

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

Result<SettingsStore> SettingsStore::open(const std::string& path, const std::vector<SettingDefault>& defaults,
                                          OpenReport& report, StoreOptions options) {
  report = OpenReport{};
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->opt = std::move(options);
  impl->log = impl->opt.logger ? impl->opt.logger : spdlog::default_logger();
  auto& log = *impl->log;
  const char* vfs = impl->vfs();

  auto note = [&](spdlog::level::level_enum level, std::string msg) {
    log.log(level, "{}", msg);
    report.messages.push_back(std::move(msg));
  };

  std::set<std::string> default_names;
  for (const auto& d : defaults) {
    if (!default_names.insert(d.name).second)
      return fail(ErrorKind::internal, fmt::format("{}: register '{}' appears twice in the defaults", path, d.name));
  }

  if (impl->opt.read_only) {
    auto db = sql::Db::open(path, SQLITE_OPEN_READONLY, vfs);
    if (!db) return std::unexpected(db.error());
    auto v = db->query_int("PRAGMA user_version", "reading the schema version");
    if (!v) return std::unexpected(v.error());
    report.schema_version_found = static_cast<int>(*v);
    if (*v != kSchemaVersion)
      return fail(ErrorKind::version, fmt::format("{}: schema version {} (this program reads {}); start the module "
                                                  "once to upgrade the database",
                                                  path, *v, kSchemaVersion));
    impl->db = std::move(*db);
  } else {
    // Leftovers of a backup or restore interrupted by a power cut.
    remove_quiet(bak_path(path, 0) + ".tmp");
    remove_quiet(bak_path(path, 0) + ".tmp-journal");
    remove_quiet(path + ".restore.tmp");

    auto restore_from_backup = [&]() -> std::optional<std::string> {
      for (int gen = 0; gen < 2; ++gen) {
        std::string candidate = bak_path(path, gen);
        if (!exists(candidate)) continue;
        if (auto problem = backup_problem(candidate, vfs)) {
          note(spdlog::level::err, fmt::format("backup {} is not usable: {}", candidate, *problem));
          continue;
        }
        remove_sidecars(path);
        if (auto s = copy_durable(candidate, path); !s) {
          note(spdlog::level::err, fmt::format("restoring {} failed: {}", candidate, s.error().message));
          continue;
        }
        return candidate;
      }
      return std::nullopt;
    };

    bool fresh = false;
    if (!exists(path)) {
      if (exists(bak_path(path, 0)) || exists(bak_path(path, 1))) {
        note(spdlog::level::err, fmt::format("settings database {} is missing but backups exist", path));
        if (auto used = restore_from_backup()) {
          report.outcome = OpenOutcome::restored_from_backup;
          report.restored_from = *used;
          note(spdlog::level::warn, fmt::format("settings database {} restored from backup {}", path, *used));
        } else {
          fresh = true;
          report.outcome = OpenOutcome::defaults_settings_lost;
          report.settings_lost = true;
        }
      } else {
        fresh = true;
        report.outcome = OpenOutcome::created;
      }
    }

    int version = 0;
    if (!fresh) {
      auto db = open_verified(path, vfs, version);
      if (db && version == 0 && (exists(bak_path(path, 0)) || exists(bak_path(path, 1)))) {
        // An empty file next to backups is a lost database, not a first start.
        db = std::unexpected(Error{ErrorKind::corrupt, fmt::format("{}: the file is empty but backups exist", path)});
      }
      if (!db && db.error().kind == ErrorKind::corrupt && report.outcome != OpenOutcome::restored_from_backup) {
        note(spdlog::level::critical, fmt::format("settings database is damaged: {}", db.error().message));
        // Keep the damaged file (and its WAL) for diagnosis, out of the way.
        std::string aside = fmt::format("{}.corrupt-{}", path, impl->now_ms());
        if (::rename(path.c_str(), aside.c_str()) != 0)
          return std::unexpected(os_error(path, "moving the damaged database aside", errno));
        if (exists(path + "-wal")) ::rename((path + "-wal").c_str(), (aside + "-wal").c_str());
        remove_sidecars(path);
        (void)fsync_path(dir_of(path), true);
        report.damaged_copy = aside;
        note(spdlog::level::warn, fmt::format("damaged database kept as {}", aside));
        if (auto used = restore_from_backup()) {
          report.outcome = OpenOutcome::restored_from_backup;
          report.restored_from = *used;
          note(spdlog::level::warn, fmt::format("settings database {} restored from backup {}; changes after that "
                                                "backup are lost",
                                                path, *used));
          db = open_verified(path, vfs, version);
        } else {
          fresh = true;
          report.outcome = OpenOutcome::defaults_settings_lost;
          report.settings_lost = true;
        }
      }
      if (!fresh) {
        if (!db) {
          note(spdlog::level::critical, db.error().message);
          return std::unexpected(db.error());
        }
        impl->db = std::move(*db);
      }
    }
    if (fresh) {
      remove_sidecars(path);
      auto db = open_configured(path, true, vfs);
      if (!db) {
        note(spdlog::level::critical, db.error().message);
        return std::unexpected(db.error());
      }
      impl->db = std::move(*db);
      version = 0;
    }
    report.schema_version_found = version;
    if (version == 0 && report.outcome == OpenOutcome::opened) report.outcome = OpenOutcome::created;

    if (version < kSchemaVersion) {
      if (version > 0) {
        // Keep the pre-upgrade file: a firmware rollback can go back to it.
        std::string pre = fmt::format("{}.pre-v{}", path, kSchemaVersion);
        remove_quiet(pre);
        auto st = impl->db.prepare("VACUUM INTO ?");
        if (st) {
          st->bind(1, std::string_view(pre));
          if (auto s = st->run("copying the database before the schema upgrade"); !s)
            note(spdlog::level::warn, s.error().message);
        }
        note(spdlog::level::info, fmt::format("settings database {}: upgrading schema v{} to v{} (old copy: {})", path,
                                              version, kSchemaVersion, pre));
      }
      if (auto s = migrate(impl->db, version, log); !s) {
        note(spdlog::level::critical, s.error().message);
        return std::unexpected(s.error());
      }
    }

    // Registers new to this database get their default: no migration needed.
    {
      auto txn = sql::Transaction::begin(impl->db, "inserting default settings");
      if (!txn) return std::unexpected(txn.error());
      auto ins = impl->db.prepare("INSERT OR IGNORE INTO settings(name, value) VALUES(?, ?)");
      if (!ins) return std::unexpected(ins.error());
      for (const auto& d : defaults) {
        ins->bind(1, std::string_view(d.name)).bind(2, d.value);
        if (auto s = ins->run("inserting a default setting"); !s) return std::unexpected(s.error());
        if (sqlite3_changes(impl->db.get()) > 0) report.added_defaults.push_back(d.name);
      }
      if (report.settings_lost) {
        auto flag = impl->db.prepare("INSERT OR REPLACE INTO meta(key, value) VALUES(?, ?)");
        if (!flag) return std::unexpected(flag.error());
        flag->bind(1, kLostKey).bind(2, std::string_view(fmt::format("{}", impl->now_ms())));
        if (auto s = flag->run("setting the settings-lost flag"); !s) return std::unexpected(s.error());
      }
      if (auto s = txn->commit("committing default settings"); !s) return std::unexpected(s.error());
    }
    if (fresh) (void)fsync_path(dir_of(path), true);
    if (!report.added_defaults.empty() && report.outcome != OpenOutcome::created)
      note(spdlog::level::info, fmt::format("settings database {}: {} new register(s) set to default (first: {})",
                                            path, report.added_defaults.size(), report.added_defaults.front()));
  }

  // Load.
  {
    auto st = impl->db.prepare("SELECT name, value FROM settings ORDER BY name");
    if (!st) return std::unexpected(st.error());
    for (;;) {
      auto row = st->step("reading settings");
      if (!row) return std::unexpected(row.error());
      if (!*row) break;
      std::string name = st->text_at(0);
      if (impl->opt.read_only || default_names.contains(name)) {
        impl->values[name] = st->int_at(1);
      } else {
        report.unknown_names.push_back(name);
      }
    }
    auto lost = impl->db.prepare("SELECT count(*) FROM meta WHERE key = ?");
    if (!lost) return std::unexpected(lost.error());
    lost->bind(1, kLostKey);
    auto row = lost->step("reading the settings-lost flag");
    if (!row) return std::unexpected(row.error());
    impl->settings_lost = *row && lost->int_at(0) > 0;
    report.settings_lost = impl->settings_lost;
  }
  if (!report.unknown_names.empty())
    note(spdlog::level::warn, fmt::format("settings database {}: {} stored setting(s) no register uses, kept and "
                                          "ignored (first: {})",
                                          path, report.unknown_names.size(), report.unknown_names.front()));

  switch (report.outcome) {
    case OpenOutcome::created:
      note(spdlog::level::info, fmt::format("settings database {} created with {} default settings", path,
                                            impl->values.size()));
      break;
    case OpenOutcome::opened:
      note(spdlog::level::info, fmt::format("settings database {} opened, intact, {} settings", path,
                                            impl->values.size()));
      break;
    case OpenOutcome::restored_from_backup: break;  // noted above
    case OpenOutcome::defaults_settings_lost:
      note(spdlog::level::critical,
           fmt::format("settings database {}: no good copy found; running on DEFAULT settings, 'settings lost' is "
                       "raised until reset",
                       path));
      break;
  }
  if (impl->settings_lost && report.outcome != OpenOutcome::defaults_settings_lost)
    note(spdlog::level::warn, fmt::format("settings database {}: 'settings lost' from an earlier start is still "
                                          "not acknowledged",
                                          path));

  if (!impl->opt.read_only && report.outcome != OpenOutcome::opened) {
    // Make the repaired/new state the newest backup at once.
    impl->backup_dirty = true;
    std::lock_guard lock(impl->mu);
    if (auto s = impl->backup_locked(); !s) log.warn("{}", s.error().message);
  }
  return SettingsStore(std::move(impl));
}

void SettingsStore::close() {
  if (!impl_) return;
  std::lock_guard lock(impl_->mu);
  if (!impl_->db) return;
  if (impl_->backup_dirty && !impl_->opt.read_only) {
    if (auto s = impl_->backup_locked(); !s) impl_->log->warn("{}", s.error().message);
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
  std::lock_guard lock(impl_->mu);
  auto changes = impl_->commit_locked(writes, source);
  if (!changes) {
    changes.error().message += "; nothing was written, the old settings stay in force";
    return changes;
  }
  if (!changes->empty() && impl_->opt.backup_on_commit) {
    if (auto s = impl_->backup_if_due_locked(); !s) impl_->log->warn("{}", s.error().message);
  }
  return changes;
}

Result<std::vector<Change>> SettingsStore::Impl::commit_locked(const std::vector<SettingWrite>& writes,
                                                               const ChangeSource& source) {
  if (!db) return fail(ErrorKind::internal, fmt::format("{}: commit on a closed settings store", path));
  if (opt.read_only)
    return fail(ErrorKind::read_only, fmt::format("{}: opened read-only; settings cannot be written", path));
  auto working = values;
  std::vector<Change> changes;
  for (const auto& w : writes) {
    auto it = working.find(w.name);
    if (it == working.end())
      return fail(ErrorKind::invalid, fmt::format("{}: unknown register '{}'; nothing written", path, w.name));
    if (it->second != w.value) {
      changes.push_back({w.name, it->second, w.value});
      it->second = w.value;
    }
  }
  if (changes.empty()) return changes;  // already durable

  const std::int64_t t = now_ms();
  auto txn = sql::Transaction::begin(db, "starting a settings write");
  if (!txn) return std::unexpected(txn.error());
  auto upd = db.prepare("UPDATE settings SET value = ? WHERE name = ?");
  if (!upd) return std::unexpected(upd.error());
  auto aud = db.prepare(
      "INSERT INTO audit(time_ms, transport, client, name, old_value, new_value) VALUES(?, ?, ?, ?, ?, ?)");
  if (!aud) return std::unexpected(aud.error());
  for (const auto& c : changes) {
    upd->bind(1, c.new_value).bind(2, std::string_view(c.name));
    if (auto s = upd->run(fmt::format("writing setting '{}'", c.name)); !s) return std::unexpected(s.error());
    aud->bind(1, t)
        .bind(2, std::string_view(source.transport))
        .bind(3, std::string_view(source.client))
        .bind(4, std::string_view(c.name))
        .bind(5, c.old_value)
        .bind(6, c.new_value);
    if (auto s = aud->run("writing the audit log"); !s) return std::unexpected(s.error());
  }
  auto prune = db.prepare("DELETE FROM audit WHERE id <= (SELECT max(id) FROM audit) - ?");
  if (!prune) return std::unexpected(prune.error());
  prune->bind(1, static_cast<std::int64_t>(std::max<std::size_t>(opt.audit_max_rows, 1)));
  if (auto s = prune->run("pruning the audit log"); !s) return std::unexpected(s.error());
  if (auto s = txn->commit("committing a settings write"); !s) return std::unexpected(s.error());
  values = std::move(working);
  backup_dirty = true;
  return changes;
}

bool SettingsStore::settings_lost() const {
  std::lock_guard lock(impl_->mu);
  return impl_->settings_lost;
}

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

Status SettingsStore::set_limits(std::size_t audit_max_rows, std::size_t history_max_rows) {
  std::lock_guard lock(impl_->mu);
  impl_->opt.audit_max_rows = std::max<std::size_t>(audit_max_rows, 1);
  impl_->opt.history_max_rows = std::max<std::size_t>(history_max_rows, 1);
  return {};
}

Result<std::int64_t> SettingsStore::record_homing_run(const HomingRun& run) {
  std::lock_guard lock(impl_->mu);
  auto& m = *impl_;
  if (m.opt.read_only) return fail(ErrorKind::read_only, fmt::format("{}: opened read-only", m.path));
  auto txn = sql::Transaction::begin(m.db, "starting to record a homing run");
  if (!txn) return std::unexpected(txn.error());
  std::int64_t id = 0;
  {
    auto ins = m.db.prepare("INSERT INTO homing_runs(start_ms, end_ms, axes, result, alarm_axis) VALUES(?, ?, ?, ?, ?)");
    if (!ins) return std::unexpected(ins.error());
    ins->bind(1, run.start_ms)
        .bind(2, run.end_ms)
        .bind(3, static_cast<std::int64_t>(run.axes))
        .bind(4, static_cast<std::int64_t>(run.result))
        .bind(5, static_cast<std::int64_t>(run.alarm_axis));
    if (auto s = ins->run("recording a homing run"); !s) return std::unexpected(s.error());
    id = sqlite3_last_insert_rowid(m.db.get());
    auto ax = m.db.prepare("INSERT INTO homing_axes(run_id, axis, correction_mm, duration_ms) VALUES(?, ?, ?, ?)");
    if (!ax) return std::unexpected(ax.error());
    for (std::size_t a = 0; a < kHistoryAxes; ++a) {
      const auto& r = run.axis[a];
      if (!r.present) continue;
      ax->bind(1, id).bind(2, static_cast<std::int64_t>(a));
      if (r.correction_mm && std::isfinite(*r.correction_mm))
        ax->bind(3, *r.correction_mm);
      else
        ax->bind_null(3);
      ax->bind(4, r.duration_ms);
      if (auto s = ax->run("recording a homing run axis"); !s) return std::unexpected(s.error());
    }
    std::int64_t cut = id - static_cast<std::int64_t>(std::max<std::size_t>(m.opt.history_max_rows, 1));
    if (cut > 0) {
      auto p1 = m.db.prepare("DELETE FROM homing_axes WHERE run_id <= ?");
      auto p2 = m.db.prepare("DELETE FROM homing_runs WHERE id <= ?");
      if (!p1) return std::unexpected(p1.error());
      if (!p2) return std::unexpected(p2.error());
      p1->bind(1, cut);
      p2->bind(1, cut);
      if (auto s = p1->run("pruning the homing history"); !s) return std::unexpected(s.error());
      if (auto s = p2->run("pruning the homing history"); !s) return std::unexpected(s.error());
    }
  }
  if (auto s = txn->commit("committing a homing run"); !s) return std::unexpected(s.error());
  m.backup_dirty = true;
  return id;
}

Result<std::vector<HomingRun>> SettingsStore::recent_runs(std::size_t n) const {
  std::lock_guard lock(impl_->mu);
  auto& m = *impl_;
  std::vector<HomingRun> runs;
  auto st = m.db.prepare("SELECT id, start_ms, end_ms, axes, result, alarm_axis FROM homing_runs ORDER BY id DESC LIMIT ?");
  if (!st) return std::unexpected(st.error());
  st->bind(1, static_cast<std::int64_t>(n));
  for (;;) {
    auto row = st->step("reading the homing history");
    if (!row) return std::unexpected(row.error());
    if (!*row) break;
    HomingRun r;
    r.id = st->int_at(0);
    r.start_ms = st->int_at(1);
    r.end_ms = st->int_at(2);
    r.axes = static_cast<std::uint8_t>(st->int_at(3));
    r.result = static_cast<std::int32_t>(st->int_at(4));
    r.alarm_axis = static_cast<std::int32_t>(st->int_at(5));
    runs.push_back(r);
  }
  auto ax = m.db.prepare("SELECT axis, correction_mm, duration_ms FROM homing_axes WHERE run_id = ?");
  if (!ax) return std::unexpected(ax.error());
  for (auto& r : runs) {
    ax->bind(1, r.id);
    for (;;) {
      auto row = ax->step("reading the homing history");
      if (!row) return std::unexpected(row.error());
      if (!*row) break;
      auto a = static_cast<std::size_t>(ax->int_at(0));
      if (a >= kHistoryAxes) continue;
      r.axis[a].present = true;
      if (!ax->null_at(1)) r.axis[a].correction_mm = ax->real_at(1);
      r.axis[a].duration_ms = ax->int_at(2);
    }
    ax->reset();
  }
  return runs;
}

Result<std::vector<AuditEntry>> SettingsStore::recent_changes(std::size_t n) const {
  std::lock_guard lock(impl_->mu);
  auto st = impl_->db.prepare(
      "SELECT id, time_ms, transport, client, name, old_value, new_value FROM audit ORDER BY id DESC LIMIT ?");
  if (!st) return std::unexpected(st.error());
  st->bind(1, static_cast<std::int64_t>(n));
  std::vector<AuditEntry> out;
  for (;;) {
    auto row = st->step("reading the audit log");
    if (!row) return std::unexpected(row.error());
    if (!*row) break;
    out.push_back({st->int_at(0), st->int_at(1), st->text_at(2), st->text_at(3), st->text_at(4), st->int_at(5),
                   st->int_at(6)});
  }
  return out;
}

Result<CorrectionSummary> SettingsStore::correction_summary(std::size_t axis, std::size_t last_n) const {
  if (axis >= kHistoryAxes)
    return fail(ErrorKind::invalid, fmt::format("axis index {} out of range (0..{})", axis, kHistoryAxes - 1));
  std::lock_guard lock(impl_->mu);
  auto st = impl_->db.prepare(
      "SELECT correction_mm FROM homing_axes WHERE axis = ? AND correction_mm IS NOT NULL "
      "ORDER BY run_id DESC LIMIT ?");
  if (!st) return std::unexpected(st.error());
  st->bind(1, static_cast<std::int64_t>(axis)).bind(2, static_cast<std::int64_t>(last_n));
  std::vector<double> xs;
  for (;;) {
    auto row = st->step("reading home corrections");
    if (!row) return std::unexpected(row.error());
    if (!*row) break;
    xs.push_back(st->real_at(0));
  }
  CorrectionSummary s;
  s.count = xs.size();
  if (xs.empty()) return s;
  auto [lo, hi] = std::minmax_element(xs.begin(), xs.end());
  s.min = *lo;
  s.max = *hi;
  s.spread = s.max - s.min;
  double sum = 0;
  for (double x : xs) sum += x;
  s.mean = sum / static_cast<double>(xs.size());
  if (xs.size() > 1) {
    double sq = 0;
    for (double x : xs) sq += (x - s.mean) * (x - s.mean);
    s.stddev = std::sqrt(sq / static_cast<double>(xs.size() - 1));
  }
  return s;
}

namespace {
struct BackupFinisher {
  void operator()(sqlite3_backup* b) const noexcept { sqlite3_backup_finish(b); }
};

// Copies the live database (including what is still in the WAL) page by page
// into `tmp`, unsynced; the caller verifies and fsyncs it once. Then marks the
// copy as a rollback-journal database (header bytes 18-19 = 1, what
// "PRAGMA journal_mode=DELETE" writes) so it opens without -wal/-shm files.
Status copy_pages(sql::Db& src, const std::string& tmp, const char* vfs) {
  auto dst = sql::Db::open(tmp, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, vfs);
  if (!dst) return std::unexpected(dst.error());
  if (auto s = dst->exec("PRAGMA journal_mode=OFF; PRAGMA synchronous=OFF", "preparing the backup file"); !s) return s;
  std::unique_ptr<sqlite3_backup, BackupFinisher> b(sqlite3_backup_init(dst->get(), "main", src.get(), "main"));
  if (!b) return std::unexpected(dst->error(sqlite3_errcode(dst->get()), "starting the backup"));
  int rc = sqlite3_backup_step(b.get(), -1);
  int finish = sqlite3_backup_finish(b.release());
  if (rc != SQLITE_DONE) return std::unexpected(dst->error(rc, "copying the database into the backup"));
  if (finish != SQLITE_OK) return std::unexpected(dst->error(finish, "finishing the backup"));
  dst->close();
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) return std::unexpected(os_error(tmp, "opening the backup", errno));
  const unsigned char rollback_mode[2] = {1, 1};
  ssize_t n = ::pwrite(fd, rollback_mode, 2, 18);
  int err = errno;
  ::close(fd);
  if (n != 2) return std::unexpected(os_error(tmp, "writing the backup header", n < 0 ? err : EIO));
  return {};
}
}  // namespace

Status SettingsStore::Impl::backup_locked() {
  const std::string bak = bak_path(path, 0);
  const std::string tmp = bak + ".tmp";
  remove_quiet(tmp);
  remove_quiet(tmp + "-journal");
  if (auto s = copy_pages(db, tmp, vfs()); !s) {
    remove_quiet(tmp);
    s.error().message = fmt::format("backup {} not written: {}", bak, s.error().message);
    return s;
  }
  if (auto problem = backup_problem(tmp, vfs())) {
    remove_quiet(tmp);
    return fail(ErrorKind::io, fmt::format("backup {} failed verification: {}", tmp, *problem));
  }
  if (auto s = fsync_path(tmp, false); !s) {
    remove_quiet(tmp);
    return s;
  }
  if (exists(bak)) {
    if (::rename(bak.c_str(), bak_path(path, 1).c_str()) != 0) {
      int err = errno;
      remove_quiet(tmp);
      return std::unexpected(os_error(bak, "rotating the previous backup", err));
    }
  }
  if (auto s = rename_durable(tmp, bak); !s) {
    remove_quiet(tmp);
    return s;
  }
  backup_dirty = false;
  backed_up_once = true;
  last_backup = std::chrono::steady_clock::now();
  log->debug("settings database {}: backup {} written", path, bak);
  return {};
}

Status SettingsStore::Impl::backup_if_due_locked() {
  if (!backup_dirty || !db || opt.read_only) return {};
  if (backed_up_once && std::chrono::steady_clock::now() - last_backup < opt.backup_min_interval) return {};
  return backup_locked();
}

Status SettingsStore::backup_if_due() {
  std::lock_guard lock(impl_->mu);
  return impl_->backup_if_due_locked();
}

Status SettingsStore::backup_now() {
  std::lock_guard lock(impl_->mu);
  if (!impl_->db) return fail(ErrorKind::internal, "backup of a closed settings store");
  return impl_->backup_locked();
}

bool SettingsStore::backup_pending() const {
  std::lock_guard lock(impl_->mu);
  return impl_->backup_dirty;
}

Status SettingsStore::check_integrity() const {
  std::lock_guard lock(impl_->mu);
  auto p = impl_->db.integrity_problems();
  if (!p) return std::unexpected(p.error());
  if (*p) return fail(ErrorKind::corrupt, fmt::format("{}: integrity check failed: {}", impl_->path, **p));
  return {};
}

}  // namespace persistence
