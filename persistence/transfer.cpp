// Export and import of all settings as a human-readable TOML file.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "persistence/settings_file.hpp"
#include "persistence/settings_store.hpp"
#include "persistence/store_impl.hpp"

namespace persistence {

Status SettingsStore::export_file(const std::string& file, const SettingsFileCodec* codec) const {
  std::string text;
  {
    std::lock_guard lock(impl_->mu);
    text = settings_file_text(impl_->values, impl_->path, impl_->now_ms(), codec);
  }
  if (auto w = write_file_atomically(file, text); !w) {
    Error e = w.error();
    e.message = "settings export: " + e.message;
    return std::unexpected(e);
  }
  impl_->log->info("settings exported to {}", file);
  return {};
}

Result<ImportReport> SettingsStore::import_file(const std::string& file, const Validator& validate,
                                                const SettingsFileCodec* codec) {
  auto read = read_settings_file(file);
  if (!read) return std::unexpected(read.error());
  const SettingsFileEntries& entries = read->entries;

  std::lock_guard lock(impl_->mu);
  auto& m = *impl_;
  ImportReport report;
  for (const auto& [name, e] : entries)
    if (!m.values.contains(name))
      return fail(ErrorKind::invalid, fmt::format("{}:{}: unknown register '{}'; nothing was imported", file, e.line,
                                                  name));
  auto raw = raw_values(file, *read, codec);
  if (!raw) return std::unexpected(raw.error());
  auto proposed = m.values;
  for (const auto& [name, value] : *raw) proposed[name] = value;
  for (const auto& [name, v] : m.values)
    if (!entries.contains(name)) report.not_in_file.push_back(name);
  if (validate) {
    if (auto rejection = validate(proposed)) {
      auto it = entries.find(rejection->name);
      if (it != entries.end())
        return fail(ErrorKind::invalid, fmt::format("{}:{}: '{}' rejected: {}; nothing was imported", file,
                                                    it->second.line, rejection->name, rejection->message));
      if (!rejection->name.empty())
        return fail(ErrorKind::invalid, fmt::format("{}: '{}' rejected: {}; nothing was imported", file,
                                                    rejection->name, rejection->message));
      return fail(ErrorKind::invalid, fmt::format("{}: rejected: {}; nothing was imported", file, rejection->message));
    }
  }
  std::vector<SettingWrite> writes;
  writes.reserve(entries.size());
  for (const auto& [name, value] : *raw) writes.push_back({name, value});
  auto changes = m.commit_locked({SettingsStore::BatchEntry{&writes, ChangeSource{"import", file}}});
  if (!changes) {
    changes.error().message += fmt::format("; nothing was imported from {}", file);
    return std::unexpected(changes.error());
  }
  if (!changes->front().empty()) {
    if (auto s = m.backup_if_due_locked(); !s) m.log->warn("{}", s.error().message);
  }
  report.changes = std::move(changes->front());
  m.log->info("settings imported from {}: {} changed, {} not in the file (kept)", file, report.changes.size(),
              report.not_in_file.size());
  return report;
}

}  // namespace persistence
