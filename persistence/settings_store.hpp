#pragma once
// Durable module settings, audit log and homing history in one SQLite file.
//
// Settings are keyed rows (register name -> raw register integer). The list of
// registers and their defaults is an input (the register table owns it), so a
// register added later only needs to appear in that list: open() inserts it
// with its default. Every write is committed (WAL, synchronous=FULL) before
// commit() returns. See persistence/README.md.
#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "persistence/error.hpp"

namespace spdlog {
class logger;
}

namespace persistence {

struct SettingsFileCodec;  // settings_file.hpp

inline constexpr int kSchemaVersion = 7;       // see schema.cpp for the history
inline constexpr std::size_t kHistoryAxes = 6;  // X Y Z A B C

struct SettingDefault {
  std::string name;
  std::int64_t value = 0;
};

// One register write as the server received it.
struct SettingWrite {
  std::string name;
  std::int64_t value = 0;
};

// One applied change (what the audit log records).
struct Change {
  std::string name;
  std::int64_t old_value = 0;
  std::int64_t new_value = 0;
};

struct ChangeSource {
  std::string transport;  // "tcp", "rtu", "cli", "import"
  std::string client;     // "192.168.0.20:50122", "unit 5", a file name...
};

struct StoreOptions {
  std::size_t audit_max_rows = 10000;    // oldest rows pruned beyond this
  std::size_t history_max_rows = 10000;  // homing runs kept
  // A verified backup (<db>.bak) is written after a commit batch unless the
  // previous one is younger than this; a later commit, backup_if_due() or
  // close() then writes it. 0 = after every commit.
  std::chrono::milliseconds backup_min_interval{1000};
  // false: commit() never writes the backup itself; the owner calls
  // backup_if_due() from an idle tick, so no acknowledged write waits for it.
  bool backup_on_commit = true;
  bool read_only = false;  // for tools: no migration, no defaults, no restore
  std::string vfs;         // SQLite VFS name; empty = default (tests inject faults)
  std::shared_ptr<spdlog::logger> logger;  // default: spdlog::default_logger()
  std::function<std::int64_t()> now_ms;    // default: system clock, unix ms
};

enum class OpenOutcome {
  created,                 // no database existed: created from the defaults
  opened,                  // opened and intact
  restored_from_backup,    // damaged: a backup was verified and restored
  defaults_settings_lost,  // damaged and no good backup: defaults, settings_lost
};
std::string_view outcome_name(OpenOutcome o);

struct OpenReport {
  OpenOutcome outcome = OpenOutcome::opened;
  bool settings_lost = false;           // latched until acknowledge_settings_lost()
  int schema_version_found = 0;         // before migration (0 = new file)
  std::string restored_from;            // backup file used, if any
  std::string damaged_copy;             // where the damaged file was moved
  std::vector<std::string> added_defaults;  // registers new to this database
  std::vector<std::string> unknown_names;   // rows no register claims (kept, ignored)
  std::vector<std::string> messages;        // what happened, also logged
};

struct AuditEntry {
  std::int64_t id = 0;
  std::int64_t time_ms = 0;
  std::string transport;
  std::string client;
  std::string name;
  std::int64_t old_value = 0;
  std::int64_t new_value = 0;
};

// Why an axis's home correction of a run is not in the correction statistics
// (stored as the number; texts in excluded_text()).
enum class Excluded : std::uint8_t {
  no = 0,                // counted (or no correction was measured)
  not_homed_before = 1,  // the axis was not homed when the cycle started: the correction is
                         // where it happened to stand (the first cycle after a start-up)
  cycle_failed = 2,      // the cycle ended with an alarm: no correction was assigned
};
std::string_view excluded_text(Excluded e);  // "not homed before the cycle"

// What one cycle measured of an axis's switch, and of its gantry (the
// engine's homing::SwitchHealth as the history keeps it; docs/health.md).
// Lengths in the axis's unit.
struct AxisHealth {
  int latch_passes = 0;
  double latch_spread_mm = 0;
  double latch_sigma_mm = 0;
  double hysteresis_mm = 0;
  double seek_latch_mm = 0;
  int chatter_edges = 0;
  double index_distance_mm = 0;
  bool index_near_edge = false;
  std::optional<double> gantry_skew_mm;  // a gantry slave's skew, when measured
  friend bool operator==(const AxisHealth&, const AxisHealth&) = default;
};

struct AxisRun {
  bool present = false;                 // axis took part and reported
  std::optional<double> correction_mm;  // assigned - believed at the reference edge; only when counted
  std::int64_t duration_ms = 0;
  Excluded excluded = Excluded::no;     // why there is no counted correction
  std::optional<AxisHealth> health;     // when the cycle homed the axis
};

// One cycle's health figures of an axis with its run (health_history).
struct HealthRecord {
  std::int64_t run_id = 0;
  std::int64_t start_ms = 0;
  AxisHealth health;
};

struct HomingRun {
  std::int64_t id = 0;  // assigned by record_homing_run
  std::int64_t start_ms = 0;
  std::int64_t end_ms = 0;
  std::uint8_t axes = 0;     // bit 0 = X ... bit 5 = C
  std::int32_t result = 0;   // 0 ok, else the alarm code
  std::int32_t alarm_axis = -1;  // -1 none / global
  std::array<AxisRun, kHistoryAxes> axis{};
};

struct CorrectionSummary {
  std::size_t count = 0;
  double mean = 0;
  double spread = 0;  // max - min
  double stddev = 0;  // sample standard deviation (0 for fewer than 2)
  double min = 0;
  double max = 0;
};

// Where an axis came to rest when the module last stopped (docs/operating.md
// "Position trust across restarts"): clean only when written by a clean
// shutdown; start-up wipes the mark (clear_clean_stops) before anything can
// move, so a run that ends any other way (kill, power cut) leaves it wiped.
// The home frame it was homed in is kept as the register values of its
// settings (mode, direction, ...): the runtime compares it with the settings
// it starts with.
struct StoredFrame {
  std::int64_t mode = 0;
  std::int64_t direction = 0;
  bool sensor_nc = false;
  std::int64_t slave_of = 0;
  std::int64_t slave_mode = 0;
  double pull_off_mm = 0;
  double switch_compensation_mm = 0;
  double home_position_mm = 0;
  std::int64_t cam_edge = 0;  // 0 unless mode is home_cam (schema v7)
  friend bool operator==(const StoredFrame&, const StoredFrame&) = default;
};
struct AxisLastStop {
  bool clean = false;
  double position_mm = 0;  // machine coordinate, in the axis's unit
  StoredFrame frame;
  std::int64_t time_ms = 0;  // when it was recorded
  friend bool operator==(const AxisLastStop&, const AxisLastStop&) = default;
};
using LastStops = std::array<std::optional<AxisLastStop>, kHistoryAxes>;  // nullopt: never recorded
// Where each simulated carriage is (homingd's simulator backend keeps them as
// a real machine keeps its carriages across a restart).
using SimCarriages = std::array<std::optional<double>, kHistoryAxes>;

// Validation of a whole proposed settings set, supplied by the register layer
// so an import follows exactly the Modbus rules. nullopt = accepted.
struct Rejection {
  std::string name;     // the register at fault, empty if none in particular
  std::string message;  // why
};
using Validator = std::function<std::optional<Rejection>(const std::map<std::string, std::int64_t>&)>;

// How the store's own connection is configured for durability, as SQLite
// reports it (for diagnostics and tests: a connection default cannot
// silently weaken what commit() promises).
struct DurabilitySettings {
  std::string journal_mode;  // "wal"
  int synchronous = -1;      // PRAGMA synchronous: 0 OFF, 1 NORMAL, 2 FULL, 3 EXTRA
};

struct ImportReport {
  std::vector<Change> changes;          // what the import changed (also audited)
  std::vector<std::string> not_in_file; // registers the file does not mention (kept)
};

class SettingsStore {
 public:
  // Opens (creating, migrating, or repairing) the database at `path`.
  // `report` says what happened; it is filled also when an error is returned.
  static Result<SettingsStore> open(const std::string& path, const std::vector<SettingDefault>& defaults,
                                    OpenReport& report, StoreOptions options = {});

  SettingsStore(SettingsStore&&) noexcept;
  SettingsStore& operator=(SettingsStore&&) noexcept;
  ~SettingsStore();  // calls close()

  // Writes a pending backup and closes the database. Idempotent.
  void close();

  const std::string& path() const;

  // The committed settings of every known register (no I/O).
  std::map<std::string, std::int64_t> load() const;
  std::optional<std::int64_t> value(const std::string& name) const;

  // Applies all writes in one transaction together with their audit rows and
  // returns after COMMIT is durable. Writes that do not change a value are not
  // audited. On any error nothing changes, on disk or in load().
  Result<std::vector<Change>> commit(const std::vector<SettingWrite>& writes, const ChangeSource& source);

  // Several clients' writes in one transaction (group commit: one fsync for
  // all of them), applied in order, each audited with its own source. The
  // changes of each, in the same order; on any error none of them is written.
  struct BatchEntry {
    const std::vector<SettingWrite>* writes = nullptr;
    ChangeSource source;
  };
  Result<std::vector<std::vector<Change>>> commit_batch(const std::vector<BatchEntry>& entries);

  // Deletes the audit rows beyond audit_max_rows, oldest first. Off the write
  // path: the runtime calls it now and then (and set_limits does), so a
  // write's answer never waits for it; the log holds at most what the
  // writes between two calls add beyond the limit.
  Status prune_audit();

  bool settings_lost() const;
  Status acknowledge_settings_lost(const ChangeSource& source);
  // A change made by a service command rather than a settings write (an
  // axis's coordinate set by hand): one audit row, pruned like the others.
  Status audit(const Change& change, const ChangeSource& source);

  Status set_limits(std::size_t audit_max_rows, std::size_t history_max_rows);

  // Homing history. The correction statistics count only the axes recorded
  // with a correction (Excluded::no).
  Result<std::int64_t> record_homing_run(const HomingRun& run);
  Result<std::vector<HomingRun>> recent_runs(std::size_t n) const;
  Result<std::vector<AuditEntry>> recent_changes(std::size_t n) const;
  // The audit rows after this id, oldest first, at most n; and the newest id (0: none).
  Result<std::vector<AuditEntry>> changes_after(std::int64_t id, std::size_t n) const;
  Result<std::int64_t> last_change_id() const;
  Result<CorrectionSummary> correction_summary(std::size_t axis, std::size_t last_n) const;
  // The health figures of the axis's last `last_n` runs that recorded them,
  // oldest first (what the trend check and the trend plot read).
  Result<std::vector<HealthRecord>> health_history(std::size_t axis, std::size_t last_n) const;

  // The last stops (schema v6, the cam edge v7; store_last_stop.cpp). record_last_stops
  // replaces the axes given (nullopt: left as they are) in one transaction,
  // durable when it returns; clear_clean_stops keeps the positions and
  // marks every axis not clean.
  Result<LastStops> last_stops() const;
  Status record_last_stops(const LastStops& stops);
  Status clear_clean_stops();
  Result<SimCarriages> sim_carriages() const;
  Status record_sim_carriages(const std::array<double, kHistoryAxes>& actual_mm);

  // Backups: `<db>.bak` (newest) and `<db>.bak.1`.
  Status backup_if_due();  // writes a pending backup if the interval passed (the write path goes on meanwhile)
  Status backup_now();
  bool backup_pending() const;
  // Checkpoints the WAL beside the writer (the monitor calls it now and then).
  Status checkpoint();

  // Full integrity check of the open database.
  Status check_integrity() const;
  Result<DurabilitySettings> durability() const;

  // Export/import (TOML, keys are register names; settings_file.hpp). Import
  // validates the whole merged set with `validate` and applies it in one
  // transaction (source "import"). With a codec (the register layer's) the
  // export spells engineering values and the import reads them; without, raw
  // values (format_version 1, which every import reads).
  Status export_file(const std::string& file, const SettingsFileCodec* codec = nullptr) const;
  Result<ImportReport> import_file(const std::string& file, const Validator& validate,
                                   const SettingsFileCodec* codec = nullptr);

  struct Impl;

 private:
  explicit SettingsStore(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace persistence
