// SettingsStore::open: find the database (store_recover.cpp), bring its schema
// up to date, give new registers their defaults, load, and say what happened.
#include <fmt/format.h>

#include <set>

#include "persistence/durable_files.hpp"
#include "persistence/schema.hpp"
#include "persistence/store_impl.hpp"

namespace persistence {

namespace {

// The names of the defaults; a register twice is a bug in the caller's list.
Result<std::set<std::string>> names_of(const std::string& path, const std::vector<SettingDefault>& defaults) {
  std::set<std::string> names;
  for (const auto& d : defaults) {
    if (!names.insert(d.name).second)
      return fail(ErrorKind::internal, fmt::format("{}: register '{}' appears twice in the defaults", path, d.name));
  }
  return names;
}

// Tools read the current schema only: no migration, no defaults, no restore.
Status open_read_only(SettingsStore::Impl& m, OpenReport& report) {
  if (auto foreign = refuse_foreign(m.path, m.vfs()); !foreign && foreign.error().kind == ErrorKind::invalid)
    return foreign;
  auto db = sql::Db::open(m.path, SQLITE_OPEN_READONLY, m.vfs());
  if (!db) return std::unexpected(db.error());
  auto v = db->query_int("PRAGMA user_version", "reading the schema version");
  if (!v) return std::unexpected(v.error());
  report.schema_version_found = static_cast<int>(*v);
  if (*v != kSchemaVersion)
    return fail(ErrorKind::version, fmt::format("{}: schema version {} (this program reads {}); start the module "
                                                "once to upgrade the database",
                                                m.path, *v, kSchemaVersion));
  m.db = std::move(*db);
  return {};
}

// Migrates an older schema, keeping the pre-upgrade file: a firmware rollback can go back to it.
Status upgrade_schema(SettingsStore::Impl& m, int version, const OpenNotes& note) {
  if (version >= kSchemaVersion) return {};
  if (version > 0) {
    std::string pre = fmt::format("{}.pre-v{}", m.path, kSchemaVersion);
    remove_quiet(pre);
    auto st = m.db.prepare("VACUUM INTO ?");
    if (st) {
      st->bind(1, std::string_view(pre));
      if (auto s = st->run("copying the database before the schema upgrade"); !s)
        note(spdlog::level::warn, s.error().message);
    }
    note(spdlog::level::info, fmt::format("settings database {}: upgrading schema v{} to v{} (old copy: {})", m.path,
                                          version, kSchemaVersion, pre));
  }
  if (auto s = schema::migrate(m.db, version, *m.log); !s) {
    note(spdlog::level::critical, s.error().message);
    return s;
  }
  return {};
}

// Registers new to this database get their default: no migration needed.
// The "settings lost" latch is written in the same transaction.
Status insert_defaults(SettingsStore::Impl& m, const std::vector<SettingDefault>& defaults, OpenReport& report) {
  auto txn = sql::Transaction::begin(m.db, "inserting default settings");
  if (!txn) return std::unexpected(txn.error());
  auto ins = m.db.prepare("INSERT OR IGNORE INTO settings(name, value) VALUES(?, ?)");
  if (!ins) return std::unexpected(ins.error());
  for (const auto& d : defaults) {
    ins->bind(1, std::string_view(d.name)).bind(2, d.value);
    if (auto s = ins->run("inserting a default setting"); !s) return std::unexpected(s.error());
    if (sqlite3_changes(m.db.get()) > 0) report.added_defaults.push_back(d.name);
  }
  if (report.settings_lost) {
    auto flag = m.db.prepare("INSERT OR REPLACE INTO meta(key, value) VALUES(?, ?)");
    if (!flag) return std::unexpected(flag.error());
    flag->bind(1, kLostKey).bind(2, std::string_view(fmt::format("{}", m.now_ms())));
    if (auto s = flag->run("setting the settings-lost flag"); !s) return std::unexpected(s.error());
  }
  return txn->commit("committing default settings");
}

Status open_writable(SettingsStore::Impl& m, const std::vector<SettingDefault>& defaults, OpenReport& report,
                     const OpenNotes& note) {
  auto found = open_or_recover(m.path, m.vfs(), m.now_ms(), report, note);
  if (!found) return std::unexpected(found.error());
  m.db = std::move(found->db);
  report.schema_version_found = found->version;
  if (found->version == 0 && report.outcome == OpenOutcome::opened) report.outcome = OpenOutcome::created;
  if (auto s = upgrade_schema(m, found->version, note); !s) return s;
  // A backup's last stops are older than the run that just ended: none of
  // them is known to be where the axis stopped last (position trust).
  if (report.outcome == OpenOutcome::restored_from_backup)
    if (auto s = m.db.exec("UPDATE last_stop SET clean = 0", "wiping the clean-stop marks of a restored backup"); !s)
      return s;
  if (auto s = insert_defaults(m, defaults, report); !s) return s;
  if (found->fresh) (void)fsync_path(dir_of(m.path), true);
  if (!report.added_defaults.empty() && report.outcome != OpenOutcome::created)
    note(spdlog::level::info, fmt::format("settings database {}: {} new register(s) set to default (first: {})",
                                          m.path, report.added_defaults.size(), report.added_defaults.front()));
  return {};
}

// The committed values of the known registers (every row for a reader) and
// the "settings lost" latch.
Status load_values(SettingsStore::Impl& m, const std::set<std::string>& known, OpenReport& report) {
  auto st = m.db.prepare("SELECT name, value FROM settings ORDER BY name");
  if (!st) return std::unexpected(st.error());
  for (;;) {
    auto row = st->step("reading settings");
    if (!row) return std::unexpected(row.error());
    if (!*row) break;
    std::string name = st->text_at(0);
    if (m.opt.read_only || known.contains(name)) {
      m.values[name] = st->int_at(1);
    } else {
      report.unknown_names.push_back(name);
    }
  }
  auto lost = m.db.prepare("SELECT count(*) FROM meta WHERE key = ?");
  if (!lost) return std::unexpected(lost.error());
  lost->bind(1, kLostKey);
  auto row = lost->step("reading the settings-lost flag");
  if (!row) return std::unexpected(row.error());
  m.settings_lost = *row && lost->int_at(0) > 0;
  report.settings_lost = m.settings_lost;
  return {};
}

void report_outcome(const SettingsStore::Impl& m, const OpenReport& report, const OpenNotes& note) {
  if (!report.unknown_names.empty())
    note(spdlog::level::warn, fmt::format("settings database {}: {} stored setting(s) no register uses, kept and "
                                          "ignored (first: {})",
                                          m.path, report.unknown_names.size(), report.unknown_names.front()));
  switch (report.outcome) {
    case OpenOutcome::created:
      note(spdlog::level::info,
           fmt::format("settings database {} created with {} default settings", m.path, m.values.size()));
      break;
    case OpenOutcome::opened:
      note(spdlog::level::info, fmt::format("settings database {} opened, intact, {} settings", m.path, m.values.size()));
      break;
    case OpenOutcome::restored_from_backup: break;  // noted when it was restored
    case OpenOutcome::defaults_settings_lost:
      note(spdlog::level::critical,
           fmt::format("settings database {}: no good copy found; running on DEFAULT settings, 'settings lost' is "
                       "raised until reset",
                       m.path));
      break;
  }
  if (m.settings_lost && report.outcome != OpenOutcome::defaults_settings_lost)
    note(spdlog::level::warn, fmt::format("settings database {}: 'settings lost' from an earlier start is still "
                                          "not acknowledged",
                                          m.path));
}

}  // namespace

Result<SettingsStore> SettingsStore::open(const std::string& path, const std::vector<SettingDefault>& defaults,
                                          OpenReport& report, StoreOptions options) {
  report = OpenReport{};
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->opt = std::move(options);
  impl->log = impl->opt.logger ? impl->opt.logger : spdlog::default_logger();
  const OpenNotes note{*impl->log, report};

  auto known = names_of(path, defaults);
  if (!known) return std::unexpected(known.error());
  if (auto s = impl->opt.read_only ? open_read_only(*impl, report) : open_writable(*impl, defaults, report, note); !s)
    return std::unexpected(s.error());
  if (auto s = load_values(*impl, *known, report); !s) return std::unexpected(s.error());
  report_outcome(*impl, report, note);

  if (!impl->opt.read_only && report.outcome != OpenOutcome::opened) {
    // Make the repaired/new state the newest backup at once.
    impl->backup_dirty = true;
    std::lock_guard lock(impl->mu);
    if (auto s = impl->backup_locked(); !s) impl->log->warn("{}", s.error().message);
  }
  return SettingsStore(std::move(impl));
}

}  // namespace persistence
