// A power cut in the middle of a storm of settings writes, at the SQLite
// layer. A SIGKILL (test_kill.cpp) keeps the page cache; a power cut keeps
// only what was synced. power_cut_vfs.cpp keeps the durable image of every
// file and, at a seeded random write, sync, truncate or delete, cuts: what
// was written since a file's last sync is lost or torn. The store is then
// opened as after a reboot and must hold every write whose commit() returned
// (the server answers Modbus only then) with its audit rows, the write in
// flight all or not at all, and open clean: intact, no restore, no
// "settings lost".
//
// Each round: reboot (open and verify), a storm cut at a random operation
// (7 in 10 rounds) or a storm and then a cut during close(), whose last
// checkpoint writes the database file. Every 10th reboot also opens with the
// default VFS and closes cleanly, so later rounds start a new WAL.
// Cuts: PERSISTENCE_POWER_CUTS (default 3000); seed: PERSISTENCE_POWER_CUT_SEED.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <deque>
#include <iostream>
#include <optional>
#include <random>
#include <sstream>

#include "helpers.hpp"
#include "power_cut_vfs.hpp"

using namespace persistence;

namespace {

constexpr int kRegisters = 10;
constexpr std::size_t kAuditMax = 300;  // above what one round writes: every acknowledged row is compared
constexpr int kMaxCommitsPerRound = 60;  // at most 4 changes each: 240 audit rows

std::uint64_t env_u64(const char* name, std::uint64_t fallback) {
  const char* v = std::getenv(name);
  if (!v || !*v) return fallback;
  return std::strtoull(v, nullptr, 10);
}

std::vector<SettingDefault> cut_defaults() {
  std::vector<SettingDefault> d;
  for (int k = 0; k < kRegisters; ++k) d.push_back({"cut.r" + std::to_string(k), 0});
  return d;
}

struct AuditRow {
  std::int64_t time_ms;
  std::string transport, client, name;
  std::int64_t old_value, new_value;
  bool operator==(const AuditRow&) const = default;
};

std::string text(const AuditRow& r) {
  std::ostringstream s;
  s << "[t=" << r.time_ms << " " << r.transport << " " << r.client << " " << r.name << " " << r.old_value << "->"
    << r.new_value << "]";
  return s.str();
}

// What the database must hold: the state after the last acknowledged commit,
// or that plus the whole of the commit the cut interrupted.
struct Expected {
  std::map<std::string, std::int64_t> values;
  std::deque<AuditRow> audit;  // oldest first, the newest kAuditMax

  struct Commit {
    std::vector<SettingWrite> writes;
    ChangeSource source;
    std::int64_t time_ms;
  };
  std::optional<Commit> in_flight;

  // What commit() applies: the changes in write order, one audit row each.
  void apply(const Commit& c) {
    for (const auto& w : c.writes) {
      auto& v = values.at(w.name);
      if (v == w.value) continue;
      audit.push_back({c.time_ms, c.source.transport, c.source.client, w.name, v, w.value});
      v = w.value;
    }
    while (audit.size() > kAuditMax) audit.pop_front();
  }
};

struct Tally {
  std::uint64_t cuts = 0, acked_commits = 0, acked_register_writes = 0, acked_audit_rows = 0;
  std::uint64_t in_flight_applied = 0, in_flight_lost = 0;
  std::uint64_t at_write = 0, at_sync = 0, at_truncate = 0, at_delete = 0, between = 0;
  std::uint64_t in_db_file = 0, in_wal = 0, in_backup = 0, during_close = 0;
  std::uint64_t unsynced_writes = 0, pieces_lost = 0, pieces_torn = 0, directory_changes_undone = 0;
};

// Empty when the reopened store holds what it must; else what is wrong.
std::string check_reopened(SettingsStore& store, const OpenReport& report, Expected& want, Tally& tally) {
  std::ostringstream why;
  if (report.outcome != OpenOutcome::opened || report.settings_lost || !report.restored_from.empty()) {
    why << "open took the path '" << outcome_name(report.outcome) << "'"
        << (report.settings_lost ? ", settings lost" : "");
    for (const auto& m : report.messages) why << "; " << m;
    return why.str();
  }
  if (auto s = store.check_integrity(); !s) return s.error().message;
  const auto values = store.load();
  if (values != want.values) {
    Expected applied = want;
    if (want.in_flight) applied.apply(*want.in_flight);
    if (!want.in_flight || values != applied.values) {
      why << "settings are neither the acknowledged state nor it plus the whole write in flight:";
      for (const auto& [name, v] : want.values)
        if (values.at(name) != v) why << " " << name << " stored " << values.at(name) << " acknowledged " << v;
      return why.str();
    }
    want = std::move(applied);
    ++tally.in_flight_applied;
  } else if (want.in_flight) {
    Expected applied = want;
    applied.apply(*want.in_flight);
    if (applied.values != want.values) ++tally.in_flight_lost;
  }
  want.in_flight.reset();
  // The newest kAuditMax rows: older ones go when the runtime prunes (off the
  // write path, now and then), which a cut may have come before.
  auto rows = store.recent_changes(kAuditMax);
  if (!rows) return rows.error().message;
  std::vector<AuditRow> got;
  for (auto it = rows->rbegin(); it != rows->rend(); ++it)
    got.push_back({it->time_ms, it->transport, it->client, it->name, it->old_value, it->new_value});
  if (!std::equal(got.begin(), got.end(), want.audit.begin(), want.audit.end())) {
    why << "audit log has " << got.size() << " rows, expected " << want.audit.size();
    for (std::size_t i = 0; i < std::max(got.size(), want.audit.size()); ++i) {
      std::string g = i < got.size() ? text(got[i]) : "(none)";
      std::string w = i < want.audit.size() ? text(want.audit[i]) : "(none)";
      if (g != w) {
        why << "; first difference at row " << i << ": stored " << g << ", expected " << w;
        break;
      }
    }
    return why.str();
  }
  return {};
}

struct Storm {
  test::TempDir dir;
  std::string db = dir.file("settings.db");
  std::mt19937_64 rng;
  std::int64_t clock = 0;    // audit time: the commit's number
  std::int64_t counter = 0;  // every register write a new value
  Expected want;
  Tally tally;
  std::string last_cut = "none yet";

  explicit Storm(std::uint64_t seed) : rng(seed) {
    for (const auto& d : cut_defaults()) want.values[d.name] = d.value;
  }

  StoreOptions options(bool through_shim) {
    StoreOptions o;
    o.logger = test::quiet_logger();
    o.audit_max_rows = kAuditMax;
    o.backup_on_commit = false;  // as homingd: backups are the monitor's, off the write path
    o.now_ms = [this] { return clock; };
    if (through_shim) o.vfs = power_cut_vfs::kName;
    return o;
  }

  // A reboot: the disk as it is is durable; open and verify.
  SettingsStore reboot(bool clean_pass_first) {
    if (clean_pass_first) {
      OpenReport report;
      auto plain = test::open_ok(db, report, options(false), cut_defaults());
      const auto problem = check_reopened(plain, report, want, tally);
      INFO("opened with the default VFS");
      REQUIRE(problem == "");
    }  // closed cleanly: the checkpoint empties the WAL and deletes it
    power_cut_vfs::reset();
    OpenReport report;
    auto store = test::open_ok(db, report, options(true), cut_defaults());
    const auto problem = check_reopened(store, report, want, tally);
    REQUIRE(problem == "");
    return store;
  }

  std::vector<SettingWrite> random_write() {
    std::vector<int> regs(kRegisters);
    for (int k = 0; k < kRegisters; ++k) regs[static_cast<std::size_t>(k)] = k;
    std::shuffle(regs.begin(), regs.end(), rng);
    std::vector<SettingWrite> w;
    const auto n = 1 + rng() % 4;  // 1 to 4 registers in one transaction
    for (std::size_t i = 0; i < n; ++i) w.push_back({"cut.r" + std::to_string(regs[i]), ++counter});
    return w;
  }

  // Commits until the cut or `limit` commits; every commit that returned is acknowledged.
  void write_storm(SettingsStore& store, int limit) {
    for (int i = 0; i < limit && !power_cut_vfs::cut_happened(); ++i) {
      Expected::Commit c{random_write(), rng() % 2 ? test::kTcp : test::kRtu, ++clock};
      auto r = store.commit(c.writes, c.source);
      if (!r) {
        INFO("commit failed: " << r.error().message);
        REQUIRE(power_cut_vfs::cut_happened());  // the only fault there is
        want.in_flight = std::move(c);
        return;
      }
      want.apply(c);
      ++tally.acked_commits;
      tally.acked_register_writes += c.writes.size();
      tally.acked_audit_rows += r->size();
      // Now and then the audit log is pruned, as the runtime's housekeeping does.
      if (rng() % 4 == 0 && !store.prune_audit()) {
        REQUIRE(power_cut_vfs::cut_happened());
        return;
      }
    }
  }

  void round(std::size_t n) {
    auto store = reboot(n % 10 == 0);
    const bool at_close = rng() % 10 >= 7;
    if (at_close) {
      write_storm(store, 1 + static_cast<int>(rng() % 30));
      power_cut_vfs::arm(1 + rng() % 40);
      store.close();  // writes the pending backup, checkpoints into the database file, deletes the WAL
      if (power_cut_vfs::cut_happened()) ++tally.during_close;
    } else {
      power_cut_vfs::arm(1 + rng() % 160);
      write_storm(store, kMaxCommitsPerRound);
    }
    power_cut_vfs::cut_now();  // if it has not come: between two operations
    store.close();
    REQUIRE(power_cut_vfs::open_files() == 0);
    const auto at = power_cut_vfs::cut_point();
    const auto s = power_cut_vfs::apply_cut(rng);
    ++tally.cuts;
    tally.at_write += at.op == "write";
    tally.at_sync += at.op == "sync";
    tally.at_truncate += at.op == "truncate";
    tally.at_delete += at.op == "delete";
    tally.between += at.op == "-";
    tally.in_db_file += at.file == "settings.db";  // only a checkpoint writes it
    tally.in_wal += at.file == "settings.db-wal";
    tally.in_backup += at.file.starts_with("settings.db.bak");  // close() writes the pending backup first
    last_cut = at.file + " " + at.op;
    tally.unsynced_writes += s.unsynced_writes;
    tally.pieces_lost += s.pieces_lost;
    tally.pieces_torn += s.pieces_torn;
    tally.directory_changes_undone += s.directory_changes_undone;
  }
};

}  // namespace

TEST_CASE("a power cut at any moment keeps every acknowledged setting and audit row and the database opens clean",
          "[persistence][power_cut]") {
  power_cut_vfs::install();
  const std::uint64_t cuts = env_u64("PERSISTENCE_POWER_CUTS", 3000);
  const std::uint64_t seed = env_u64("PERSISTENCE_POWER_CUT_SEED", 1);
  Storm storm(seed);
  {
    OpenReport report;
    auto created = test::open_ok(storm.db, report, storm.options(false), cut_defaults());
    REQUIRE(report.outcome == OpenOutcome::created);
  }
  for (std::uint64_t n = 0; n < cuts; ++n) {
    INFO("round " << n << " (replay: PERSISTENCE_POWER_CUT_SEED=" << seed << " PERSISTENCE_POWER_CUTS=" << n + 1
                  << "); the reboot checks the cut of the round before, at: " << storm.last_cut);
    storm.round(n);
  }
  {
    OpenReport report;
    auto last = test::open_ok(storm.db, report, storm.options(false), cut_defaults());
    INFO("the last cut came at: " << storm.last_cut);
    REQUIRE(check_reopened(last, report, storm.want, storm.tally) == "");
  }
  const auto& t = storm.tally;
  std::cout << "power cuts: " << t.cuts << " (at a write " << t.at_write << ", a sync " << t.at_sync
            << ", a truncate " << t.at_truncate << ", a delete " << t.at_delete << ", between operations "
            << t.between << "; in the WAL " << t.in_wal << ", in the database file " << t.in_db_file
            << ", in a backup " << t.in_backup << ", during close " << t.during_close
            << "); acknowledged commits verified: " << t.acked_commits << " (" << t.acked_register_writes
            << " register writes, " << t.acked_audit_rows << " audit rows); write in flight found whole "
            << t.in_flight_applied << ", found absent " << t.in_flight_lost << "; unsynced writes cut "
            << t.unsynced_writes << " (512-byte pieces lost " << t.pieces_lost << ", torn " << t.pieces_torn
            << "), directory changes undone " << t.directory_changes_undone << "\n";
  if (cuts >= 1000) {  // the storm reached the moments that matter, not only the quiet ones
    CHECK(t.at_sync > 0);
    CHECK(t.in_db_file > 0);
    CHECK(t.in_flight_applied > 0);
    CHECK(t.in_flight_lost > 0);
    CHECK(t.pieces_torn > 0);
  }
}
