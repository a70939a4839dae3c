// The last stops (position trust across restarts): kept across a restart,
// clean only when a clean shutdown wrote them. homingd wipes the clean marks
// at start, before anything can move; a run that ends any other way (SIGKILL,
// a power cut) finds them wiped. tests/server/trust_e2e_test.cpp runs the
// same with the real daemon.
#include <catch2/catch.hpp>

#include <limits>
#include <random>

#include "helpers.hpp"
#include "power_cut_vfs.hpp"

using namespace persistence;

namespace {

AxisLastStop stop_at(double position_mm, bool clean) {
  AxisLastStop s;
  s.clean = clean;
  s.position_mm = position_mm;
  s.frame = StoredFrame{2, 0, false, 0, 0, 1.0, 0.0, -1.5, 0};
  s.time_ms = 1234;
  return s;
}

LastStops all_at(double base_mm, bool clean) {
  LastStops stops{};
  for (std::size_t a = 0; a < kHistoryAxes; ++a) stops[a] = stop_at(base_mm + static_cast<double>(a), clean);
  return stops;
}

LastStops read_stops(const std::string& db) {
  OpenReport report;
  auto store = test::open_ok(db, report);
  auto stops = store.last_stops();
  REQUIRE(stops);
  return *stops;
}

}  // namespace

TEST_CASE("the last stops and the simulator's carriages survive a restart", "[persistence][trust]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  {
    auto store = test::open_ok(db, report);
    auto none = store.last_stops();
    REQUIRE(none);
    for (const auto& s : *none) CHECK_FALSE(s.has_value());  // a new database knows of no stop
    REQUIRE(store.record_last_stops(all_at(10.25, true)));
    REQUIRE(store.record_sim_carriages({1.5, -2.25, 3, 4, 5, 6}));
  }
  auto store = test::open_ok(db, report);
  auto stops = store.last_stops();
  REQUIRE(stops);
  CHECK(*stops == all_at(10.25, true));
  auto carriages = store.sim_carriages();
  REQUIRE(carriages);
  CHECK((*carriages)[0] == 1.5);
  CHECK((*carriages)[1] == -2.25);
  CHECK((*carriages)[5] == 6);
}

TEST_CASE("wiping the clean marks keeps the positions, and a later clean shutdown marks them again",
          "[persistence][trust]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  auto store = test::open_ok(db, report);
  REQUIRE(store.record_last_stops(all_at(5, true)));
  REQUIRE(store.clear_clean_stops());
  auto stops = store.last_stops();
  REQUIRE(stops);
  CHECK(*stops == all_at(5, false));
  // Only the axes given are replaced.
  LastStops x_only{};
  x_only[0] = stop_at(7, true);
  REQUIRE(store.record_last_stops(x_only));
  stops = store.last_stops();
  REQUIRE(stops);
  CHECK((*stops)[0]->clean);
  CHECK((*stops)[0]->position_mm == 7);
  CHECK_FALSE((*stops)[1]->clean);
}

TEST_CASE("a position that is not a number is kept as no clean stop", "[persistence][trust]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  auto store = test::open_ok(db, report);
  LastStops stops{};
  stops[0] = stop_at(std::numeric_limits<double>::quiet_NaN(), true);
  REQUIRE(store.record_last_stops(stops));
  auto kept = store.last_stops();
  REQUIRE(kept);
  CHECK_FALSE((*kept)[0]->clean);
}

TEST_CASE("a database restored from its backup trusts no last stop: the backup is older than the last run",
          "[persistence][trust][fault]") {
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  OpenReport report;
  {
    auto store = test::open_ok(db, report);
    REQUIRE(store.record_last_stops(all_at(3, true)));
    REQUIRE(store.backup_now());
  }
  test::smash(db, 0, 100);
  auto store = test::open_ok(db, report);
  REQUIRE(report.outcome == OpenOutcome::restored_from_backup);
  auto stops = store.last_stops();
  REQUIRE(stops);
  CHECK(*stops == all_at(3, false));
}

TEST_CASE("a power cut after the start wiped the clean marks leaves no axis clean, whatever it cuts",
          "[persistence][trust][power_cut]") {
  power_cut_vfs::install();
  std::mt19937_64 rng(7);
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  for (int k = 1; k <= 60; ++k) {
    CAPTURE(k);
    {
      OpenReport report;
      auto store = test::open_ok(db, report);
      REQUIRE(store.record_last_stops(all_at(k, true)));  // the last run's clean shutdown
    }
    power_cut_vfs::reset();
    {
      auto o = test::options();
      o.vfs = power_cut_vfs::kName;
      o.backup_on_commit = false;
      OpenReport report;
      auto store = test::open_ok(db, report, o);
      REQUIRE(store.clear_clean_stops());  // homingd's start, before anything can move
      power_cut_vfs::arm(static_cast<std::uint64_t>(k));
      // The run: settings written, carriages kept, until the power goes.
      for (int i = 0; i < 20 && !power_cut_vfs::cut_happened(); ++i) {
        (void)store.commit({{"global.watchdog_ms", 600 + i}}, test::kTcp);
        (void)store.record_sim_carriages({double(i), 0, 0, 0, 0, 0});
      }
      power_cut_vfs::cut_now();
      store.close();
    }
    REQUIRE(power_cut_vfs::open_files() == 0);
    (void)power_cut_vfs::apply_cut(rng);
    CHECK(read_stops(db) == all_at(k, false));
  }
}

TEST_CASE("a power cut during the clean shutdown's write leaves the stops as written or as wiped, never a mix",
          "[persistence][trust][power_cut]") {
  power_cut_vfs::install();
  std::mt19937_64 rng(11);
  test::TempDir dir;
  const auto db = dir.file("settings.db");
  int written = 0, wiped = 0;
  for (int k = 1; k <= 40; ++k) {
    CAPTURE(k);
    {
      OpenReport report;
      auto store = test::open_ok(db, report);
      REQUIRE(store.record_last_stops(all_at(0, false)));  // as the start left them
    }
    power_cut_vfs::reset();
    bool acknowledged = false;
    {
      auto o = test::options();
      o.vfs = power_cut_vfs::kName;
      o.backup_on_commit = false;
      OpenReport report;
      auto store = test::open_ok(db, report, o);
      power_cut_vfs::arm(static_cast<std::uint64_t>(k));
      acknowledged = store.record_last_stops(all_at(100, true)).has_value();
      store.close();
      power_cut_vfs::cut_now();
    }
    REQUIRE(power_cut_vfs::open_files() == 0);
    (void)power_cut_vfs::apply_cut(rng);
    const LastStops after = read_stops(db);
    if (after == all_at(100, true)) {
      ++written;
    } else {
      CHECK_FALSE(acknowledged);  // a write that returned is never lost
      CHECK(after == all_at(0, false));
      ++wiped;
    }
  }
  // The cut came both before and after the commit over the rounds.
  CHECK(written > 0);
  CHECK(wiped > 0);
}
