// The homing history and the audit log: recorded per run, pruned to their
// limits, read newest first; the home correction per axis summarised.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "persistence/store_impl.hpp"

namespace persistence {

namespace {

// The health columns of homing_axes (schema v5), in the order bind_health
// binds and health_at reads them.
constexpr std::string_view kHealthColumns =
    "latch_passes, latch_spread_mm, latch_sigma_mm, hysteresis_mm, seek_latch_mm, chatter_edges, "
    "index_distance_mm, index_near_edge, gantry_skew_mm";
constexpr int kHealthColumnCount = 9;

void bind_real(sql::Stmt& st, int at, std::optional<double> v) {
  if (v && std::isfinite(*v)) st.bind(at, *v);
  else st.bind_null(at);
}

// A finite figure, else 0 (a length the engine could not measure is no
// reason to lose the row).
double finite(double v) { return std::isfinite(v) ? v : 0.0; }

void bind_health(sql::Stmt& st, int first, const std::optional<AxisHealth>& h) {
  if (!h) {
    for (int k = 0; k < kHealthColumnCount; ++k) st.bind_null(first + k);
    return;
  }
  st.bind(first, static_cast<std::int64_t>(h->latch_passes))
      .bind(first + 1, finite(h->latch_spread_mm))
      .bind(first + 2, finite(h->latch_sigma_mm))
      .bind(first + 3, finite(h->hysteresis_mm))
      .bind(first + 4, finite(h->seek_latch_mm))
      .bind(first + 5, static_cast<std::int64_t>(h->chatter_edges))
      .bind(first + 6, finite(h->index_distance_mm))
      .bind(first + 7, static_cast<std::int64_t>(h->index_near_edge ? 1 : 0));
  bind_real(st, first + 8, h->gantry_skew_mm);
}

// The figures read from the columns starting at `first`; none when the row has none.
std::optional<AxisHealth> health_at(const sql::Stmt& st, int first) {
  if (st.null_at(first)) return std::nullopt;
  AxisHealth h;
  h.latch_passes = static_cast<int>(st.int_at(first));
  h.latch_spread_mm = st.real_at(first + 1);
  h.latch_sigma_mm = st.real_at(first + 2);
  h.hysteresis_mm = st.real_at(first + 3);
  h.seek_latch_mm = st.real_at(first + 4);
  h.chatter_edges = static_cast<int>(st.int_at(first + 5));
  h.index_distance_mm = st.real_at(first + 6);
  h.index_near_edge = st.int_at(first + 7) != 0;
  if (!st.null_at(first + 8)) h.gantry_skew_mm = st.real_at(first + 8);
  return h;
}

}  // namespace

std::string_view excluded_text(Excluded e) {
  switch (e) {
    case Excluded::no: return "counted";
    case Excluded::not_homed_before: return "not homed before the cycle";
    case Excluded::cycle_failed: return "the cycle ended with an alarm";
  }
  return "unknown reason";
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
    auto ax = m.db.prepare(fmt::format(
        "INSERT INTO homing_axes(run_id, axis, correction_mm, duration_ms, excluded, {}) "
        "VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
        kHealthColumns));
    if (!ax) return std::unexpected(ax.error());
    for (std::size_t a = 0; a < kHistoryAxes; ++a) {
      const auto& r = run.axis[a];
      if (!r.present) continue;
      ax->bind(1, id).bind(2, static_cast<std::int64_t>(a));
      bind_real(*ax, 3, r.correction_mm);
      ax->bind(4, r.duration_ms).bind(5, static_cast<std::int64_t>(r.excluded));
      bind_health(*ax, 6, r.health);
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
  auto ax = m.db.prepare(
      fmt::format("SELECT axis, correction_mm, duration_ms, excluded, {} FROM homing_axes WHERE run_id = ?",
                  kHealthColumns));
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
      r.axis[a].excluded = static_cast<Excluded>(ax->int_at(3));
      r.axis[a].health = health_at(*ax, 4);
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

Result<std::vector<AuditEntry>> SettingsStore::changes_after(std::int64_t id, std::size_t n) const {
  std::lock_guard lock(impl_->mu);
  auto st = impl_->db.prepare(
      "SELECT id, time_ms, transport, client, name, old_value, new_value FROM audit WHERE id > ? ORDER BY id LIMIT ?");
  if (!st) return std::unexpected(st.error());
  st->bind(1, id).bind(2, static_cast<std::int64_t>(n));
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

Result<std::int64_t> SettingsStore::last_change_id() const {
  std::lock_guard lock(impl_->mu);
  return impl_->db.query_int("SELECT coalesce(max(id), 0) FROM audit", "reading the audit log");
}

Result<CorrectionSummary> SettingsStore::correction_summary(std::size_t axis, std::size_t last_n) const {
  if (axis >= kHistoryAxes)
    return fail(ErrorKind::invalid, fmt::format("axis index {} out of range (0..{})", axis, kHistoryAxes - 1));
  std::lock_guard lock(impl_->mu);
  auto st = impl_->db.prepare(
      "SELECT correction_mm FROM homing_axes WHERE axis = ? AND correction_mm IS NOT NULL AND excluded = 0 "
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

Result<std::vector<HealthRecord>> SettingsStore::health_history(std::size_t axis, std::size_t last_n) const {
  if (axis >= kHistoryAxes)
    return fail(ErrorKind::invalid, fmt::format("axis index {} out of range (0..{})", axis, kHistoryAxes - 1));
  std::lock_guard lock(impl_->mu);
  auto st = impl_->db.prepare(fmt::format(
      "SELECT r.id, r.start_ms, {} FROM homing_axes AS a JOIN homing_runs AS r ON r.id = a.run_id "
      "WHERE a.axis = ? AND a.latch_passes IS NOT NULL ORDER BY a.run_id DESC LIMIT ?",
      kHealthColumns));
  if (!st) return std::unexpected(st.error());
  st->bind(1, static_cast<std::int64_t>(axis)).bind(2, static_cast<std::int64_t>(last_n));
  std::vector<HealthRecord> out;
  for (;;) {
    auto row = st->step("reading the health figures");
    if (!row) return std::unexpected(row.error());
    if (!*row) break;
    out.push_back({st->int_at(0), st->int_at(1), *health_at(*st, 2)});
  }
  std::reverse(out.begin(), out.end());  // oldest first
  return out;
}

}  // namespace persistence
