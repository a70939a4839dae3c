// The last stops (schema v6, the home cam's edge v7): where each axis came to rest when the module
// last stopped, and whether that stop was clean; and the simulator's
// carriages. One row per axis, replaced whole, committed before returning.
#include <fmt/format.h>

#include <cmath>

#include "persistence/store_impl.hpp"

namespace persistence {

namespace {

Status writable(const SettingsStore::Impl& m) {
  if (m.opt.read_only) return fail(ErrorKind::read_only, fmt::format("{}: opened read-only", m.path));
  return {};
}

double finite(double v) { return std::isfinite(v) ? v : 0.0; }

}  // namespace

Result<LastStops> SettingsStore::last_stops() const {
  std::lock_guard lock(impl_->mu);
  auto& m = *impl_;
  auto st = m.db.prepare(
      "SELECT axis, clean, position_mm, mode, direction, sensor_nc, slave_of, slave_mode, pull_off_mm, "
      "switch_compensation_mm, home_position_mm, time_ms, cam_edge FROM last_stop ORDER BY axis");
  if (!st) return std::unexpected(st.error());
  LastStops out{};
  for (;;) {
    auto row = st->step("reading the last stops");
    if (!row) return std::unexpected(row.error());
    if (!*row) break;
    const std::int64_t axis = st->int_at(0);
    if (axis < 0 || axis >= static_cast<std::int64_t>(kHistoryAxes)) continue;
    AxisLastStop s;
    s.clean = st->int_at(1) != 0;
    s.position_mm = st->real_at(2);
    s.frame.mode = st->int_at(3);
    s.frame.direction = st->int_at(4);
    s.frame.sensor_nc = st->int_at(5) != 0;
    s.frame.slave_of = st->int_at(6);
    s.frame.slave_mode = st->int_at(7);
    s.frame.pull_off_mm = st->real_at(8);
    s.frame.switch_compensation_mm = st->real_at(9);
    s.frame.home_position_mm = st->real_at(10);
    s.time_ms = st->int_at(11);
    s.frame.cam_edge = st->int_at(12);
    out[static_cast<std::size_t>(axis)] = s;
  }
  return out;
}

Status SettingsStore::record_last_stops(const LastStops& stops) {
  std::lock_guard lock(impl_->mu);
  auto& m = *impl_;
  if (auto w = writable(m); !w) return w;
  auto txn = sql::Transaction::begin(m.db, "starting to record the last stops");
  if (!txn) return std::unexpected(txn.error());
  {
    auto ins = m.db.prepare(
        "INSERT OR REPLACE INTO last_stop(axis, clean, position_mm, mode, direction, sensor_nc, slave_of, "
        "slave_mode, pull_off_mm, switch_compensation_mm, home_position_mm, time_ms, cam_edge) "
        "VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    if (!ins) return std::unexpected(ins.error());
    const std::int64_t now = m.now_ms();
    for (std::size_t a = 0; a < kHistoryAxes; ++a) {
      if (!stops[a]) continue;
      const AxisLastStop& s = *stops[a];
      // A position that is not a number is no position to trust.
      const bool clean = s.clean && std::isfinite(s.position_mm);
      ins->bind(1, static_cast<std::int64_t>(a))
          .bind(2, static_cast<std::int64_t>(clean ? 1 : 0))
          .bind(3, finite(s.position_mm))
          .bind(4, s.frame.mode)
          .bind(5, s.frame.direction)
          .bind(6, static_cast<std::int64_t>(s.frame.sensor_nc ? 1 : 0))
          .bind(7, s.frame.slave_of)
          .bind(8, s.frame.slave_mode)
          .bind(9, finite(s.frame.pull_off_mm))
          .bind(10, finite(s.frame.switch_compensation_mm))
          .bind(11, finite(s.frame.home_position_mm))
          .bind(12, s.time_ms != 0 ? s.time_ms : now)
          .bind(13, s.frame.cam_edge);
      if (auto r = ins->run("recording the last stop of an axis"); !r) return r;
    }
  }
  if (auto s = txn->commit("committing the last stops"); !s) return s;
  m.backup_dirty = true;
  return {};
}

Status SettingsStore::clear_clean_stops() {
  std::lock_guard lock(impl_->mu);
  auto& m = *impl_;
  if (auto w = writable(m); !w) return w;
  if (auto s = m.db.exec("UPDATE last_stop SET clean = 0 WHERE clean != 0", "wiping the clean-stop marks"); !s)
    return s;
  m.backup_dirty = true;
  return {};
}

Result<SimCarriages> SettingsStore::sim_carriages() const {
  std::lock_guard lock(impl_->mu);
  auto& m = *impl_;
  auto st = m.db.prepare("SELECT axis, actual_mm FROM sim_carriages ORDER BY axis");
  if (!st) return std::unexpected(st.error());
  SimCarriages out{};
  for (;;) {
    auto row = st->step("reading the simulator's carriages");
    if (!row) return std::unexpected(row.error());
    if (!*row) break;
    const std::int64_t axis = st->int_at(0);
    if (axis < 0 || axis >= static_cast<std::int64_t>(kHistoryAxes)) continue;
    if (const double x = st->real_at(1); std::isfinite(x)) out[static_cast<std::size_t>(axis)] = x;
  }
  return out;
}

Status SettingsStore::record_sim_carriages(const std::array<double, kHistoryAxes>& actual_mm) {
  std::lock_guard lock(impl_->mu);
  auto& m = *impl_;
  if (auto w = writable(m); !w) return w;
  auto txn = sql::Transaction::begin(m.db, "starting to record the simulator's carriages");
  if (!txn) return std::unexpected(txn.error());
  {
    auto ins = m.db.prepare("INSERT OR REPLACE INTO sim_carriages(axis, actual_mm) VALUES(?, ?)");
    if (!ins) return std::unexpected(ins.error());
    for (std::size_t a = 0; a < kHistoryAxes; ++a) {
      if (!std::isfinite(actual_mm[a])) continue;
      ins->bind(1, static_cast<std::int64_t>(a)).bind(2, actual_mm[a]);
      if (auto r = ins->run("recording a simulator carriage"); !r) return r;
    }
  }
  return txn->commit("committing the simulator's carriages");
}

}  // namespace persistence
