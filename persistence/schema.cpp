#include "persistence/schema.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "persistence/settings_store.hpp"
#include "persistence/sqlite_handle.hpp"

namespace persistence::schema {

namespace {

// v1 (first release): settings only.
constexpr std::string_view kV1 = R"sql(
CREATE TABLE settings(
  name  TEXT PRIMARY KEY NOT NULL,
  value INTEGER NOT NULL
) WITHOUT ROWID;
)sql";

// v2: audit log, with transport and client in one "source" text ("tcp 10.0.0.5").
constexpr std::string_view kV2 = R"sql(
CREATE TABLE audit(
  id        INTEGER PRIMARY KEY AUTOINCREMENT,
  time_ms   INTEGER NOT NULL,
  source    TEXT NOT NULL,
  name      TEXT NOT NULL,
  old_value INTEGER,
  new_value INTEGER NOT NULL
);
)sql";

// v3: audit source split into transport + client; homing history; meta flags.
constexpr std::string_view kV3 = R"sql(
CREATE TABLE audit_v3(
  id        INTEGER PRIMARY KEY AUTOINCREMENT,
  time_ms   INTEGER NOT NULL,
  transport TEXT NOT NULL,
  client    TEXT NOT NULL,
  name      TEXT NOT NULL,
  old_value INTEGER NOT NULL,
  new_value INTEGER NOT NULL
);
INSERT INTO audit_v3(id, time_ms, transport, client, name, old_value, new_value)
  SELECT id, time_ms,
         CASE WHEN instr(source, ' ') > 0 THEN substr(source, 1, instr(source, ' ') - 1) ELSE source END,
         CASE WHEN instr(source, ' ') > 0 THEN substr(source, instr(source, ' ') + 1) ELSE '' END,
         name, coalesce(old_value, new_value), new_value
  FROM audit ORDER BY id;
DROP TABLE audit;
ALTER TABLE audit_v3 RENAME TO audit;

CREATE TABLE meta(
  key   TEXT PRIMARY KEY NOT NULL,
  value TEXT NOT NULL
) WITHOUT ROWID;

CREATE TABLE homing_runs(
  id         INTEGER PRIMARY KEY AUTOINCREMENT,
  start_ms   INTEGER NOT NULL,
  end_ms     INTEGER NOT NULL,
  axes       INTEGER NOT NULL,
  result     INTEGER NOT NULL,
  alarm_axis INTEGER NOT NULL
);
CREATE TABLE homing_axes(
  run_id        INTEGER NOT NULL,
  axis          INTEGER NOT NULL,
  correction_mm REAL,
  duration_ms   INTEGER NOT NULL,
  PRIMARY KEY(run_id, axis)
) WITHOUT ROWID;
CREATE INDEX homing_axes_by_axis ON homing_axes(axis, run_id);
)sql";

// v4: why a run's home correction of an axis is not in the statistics
// (persistence::Excluded). Runs that ended with an alarm have no correction:
// marked as such; a correction of an earlier run stays counted (whether the
// axis was homed before it was not recorded).
constexpr std::string_view kV4 = R"sql(
ALTER TABLE homing_axes ADD COLUMN excluded INTEGER NOT NULL DEFAULT 0;
UPDATE homing_axes SET excluded = 2
  WHERE correction_mm IS NULL AND run_id IN (SELECT id FROM homing_runs WHERE result != 0);
)sql";

// v5: the switch health figures of each axis's cycle (docs/health.md) and a
// gantry slave's skew, kept with its history row for the trend check. NULL in
// rows of older databases and of axes whose cycle found no reference.
constexpr std::string_view kV5 = R"sql(
ALTER TABLE homing_axes ADD COLUMN latch_passes INTEGER;
ALTER TABLE homing_axes ADD COLUMN latch_spread_mm REAL;
ALTER TABLE homing_axes ADD COLUMN latch_sigma_mm REAL;
ALTER TABLE homing_axes ADD COLUMN hysteresis_mm REAL;
ALTER TABLE homing_axes ADD COLUMN seek_latch_mm REAL;
ALTER TABLE homing_axes ADD COLUMN chatter_edges INTEGER;
ALTER TABLE homing_axes ADD COLUMN index_distance_mm REAL;
ALTER TABLE homing_axes ADD COLUMN index_near_edge INTEGER;
ALTER TABLE homing_axes ADD COLUMN gantry_skew_mm REAL;
)sql";

// v6: where each axis came to rest when the module last stopped, whether it
// stopped cleanly and the home frame it was homed in (position trust across
// restarts), and where the simulator's carriages are.
constexpr std::string_view kV6 = R"sql(
CREATE TABLE last_stop(
  axis                   INTEGER PRIMARY KEY NOT NULL,
  clean                  INTEGER NOT NULL,
  position_mm            REAL NOT NULL,
  mode                   INTEGER NOT NULL,
  direction              INTEGER NOT NULL,
  sensor_nc              INTEGER NOT NULL,
  slave_of               INTEGER NOT NULL,
  slave_mode             INTEGER NOT NULL,
  pull_off_mm            REAL NOT NULL,
  switch_compensation_mm REAL NOT NULL,
  home_position_mm       REAL NOT NULL,
  time_ms                INTEGER NOT NULL
) WITHOUT ROWID;
CREATE TABLE sim_carriages(
  axis      INTEGER PRIMARY KEY NOT NULL,
  actual_mm REAL NOT NULL
) WITHOUT ROWID;
)sql";

// v7: which edge of a home cam an axis was homed on, as part of its home
// frame. A stop recorded before keeps the frame it was homed in: the edge
// then set for the axis, when its method was a home cam (11; never one side
// of a gantry: the rule set refuses that pair); 0 otherwise, as the engine's
// frame has it.
constexpr std::string_view kV7 = R"sql(
ALTER TABLE last_stop ADD COLUMN cam_edge INTEGER NOT NULL DEFAULT 0;
UPDATE last_stop SET cam_edge = COALESCE((
  SELECT value FROM settings WHERE name = 'axis.' || substr('xyzabc', last_stop.axis + 1, 1) || '.cam_edge'), 0)
 WHERE mode = 11;
)sql";

}  // namespace

const std::vector<Step>& steps() {
  static const std::vector<Step> all{
      {1, "settings table", kV1},
      {2, "audit log", kV2},
      {3, "audit transport/client, homing history, meta", kV3},
      {4, "why a home correction is excluded from the statistics", kV4},
      {5, "switch health figures and gantry skew per axis and run", kV5},
      {6, "last stop of each axis (position trust) and the simulator's carriages", kV6},
      {7, "the home cam's edge in each axis's last stop", kV7},
  };
  static_assert(kSchemaVersion == 7, "append a migration step when raising kSchemaVersion");
  return all;
}

Status migrate(sql::Db& db, int from, spdlog::logger& log) {
  const auto& all = steps();
  for (int v = from; v < kSchemaVersion; ++v) {
    const auto& step = all.at(static_cast<std::size_t>(v));
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

}  // namespace persistence::schema
