// The runtime's side of the position trust (docs/homing-methods.md "Position
// trust and the reference check"), with the control loop stepped by hand on
// the simulator: the kept last stops reach the engine, and a reference check
// is no homing cycle in the events the plant hears of.
#include <catch2/catch.hpp>

#include <algorithm>
#include <map>
#include <memory>

#include "homing/last_stop.hpp"
#include "homing/sim/simulator_io.hpp"
#include "registers/defaults.hpp"
#include "registers/sim_bindings.hpp"
#include "server/control_loop.hpp"
#include "server/last_stops.hpp"
#include "homing/gantry.hpp"
#include "persistence/settings_store.hpp"
#include "tests/support/captured_log.hpp"
#include "tests/support/temp_dir.hpp"

namespace {

homing::Settings default_settings() {
  std::map<std::string, std::int64_t> raw;
  for (const auto& [name, value] : registers::persisted_defaults()) raw[name] = value;
  return registers::settings_from_raw(raw).settings;
}

std::unique_ptr<server::ControlLoop> loop_with_carriages(const homing::Settings& settings,
                                                         const std::array<double, homing::kAxisCount>* carriages) {
  homing::sim::MachineConfig config = registers::default_sim_config();
  if (carriages)
    for (std::size_t a = 0; a < homing::kAxisCount; ++a) config.axes[a].actual_position_mm = (*carriages)[a];
  return std::make_unique<server::ControlLoop>(settings, std::make_unique<homing::sim::SimulatorIo>(config), 1000, 1.0);
}

// Runs the command, then periods until nothing homes or moves.
void run_command(server::ControlLoop& loop, const homing::Commands& c) {
  loop.submit(c, false);
  loop.run_period(0.001);
  for (int i = 0; i < 120'000; ++i) {
    const homing::Status st = loop.snapshot().status;
    bool busy = st.homing;
    for (const auto& a : st.axes) busy = busy || a.busy;
    if (!busy) return;
    loop.run_period(0.001);
  }
  FAIL("still busy after 120 s of machine time");
}

// The kinds of the events written after `after`.
std::vector<server::StatusEventKind> events_since(const server::ControlLoop& loop, std::uint64_t after) {
  const server::Snapshot s = loop.snapshot();
  std::vector<server::StatusEventKind> kinds;
  for (std::uint64_t seq = after + 1; seq <= s.events.written(); ++seq)
    if (const auto* e = s.events.find(seq)) kinds.push_back(e->kind);
  return kinds;
}

}  // namespace

TEST_CASE("the control loop gives the engine the kept last stops, and a reference check sends no cycle events") {
  const homing::Settings settings = default_settings();
  homing::LastStops stops{};
  std::array<double, homing::kAxisCount> carriages{};
  {
    auto before = loop_with_carriages(settings, nullptr);
    homing::Commands home;
    home.home_all = true;
    const std::uint64_t written = before->snapshot().events.written();
    run_command(*before, home);
    const server::Snapshot s = before->snapshot();
    REQUIRE(s.status.state == homing::MachineState::homed);
    // A homing cycle is news: started and ended.
    const auto kinds = events_since(*before, written);
    CHECK(std::count(kinds.begin(), kinds.end(), server::StatusEventKind::cycle_started) == 1);
    CHECK(std::count(kinds.begin(), kinds.end(), server::StatusEventKind::cycle_ended) == 1);
    stops = homing::last_stops_at_shutdown(settings, s.status, s.outputs);
    for (std::size_t a = 0; a < homing::kAxisCount; ++a) carriages[a] = s.sim.axes[a].actual_position_mm;
  }
  REQUIRE(stops[0].clean);

  auto after = loop_with_carriages(settings, &carriages);
  CHECK(after->snapshot().status.axes[0].trust == homing::Trust::unknown);  // nothing given yet
  after->restore_last_stops(stops);
  after->run_period(0);
  CHECK(after->snapshot().status.axes[0].trust == homing::Trust::last_stop_clean);
  CHECK(after->snapshot().status.axes[0].position_mm == Approx(stops[0].position_mm));

  const std::uint64_t written = after->snapshot().events.written();
  homing::Commands check;
  check.refcheck_axes = homing::axis_bit(0);
  run_command(*after, check);
  const homing::Status st = after->snapshot().status;
  CHECK(st.last_command_result == homing::CommandResult::accepted);
  CHECK(st.axes[0].trust == homing::Trust::reference_checked);
  CHECK(st.homing_cycles == 0);
  CHECK(events_since(*after, written).empty());
}

TEST_CASE("a kept last stop carries every setting of its home frame to the database and back") {
  // A field left out on either side would make a frame that changed look
  // unchanged after a restart (or the other way round).
  homing::LastStops stops{};
  homing::LastStop& s = stops[3];
  s.clean = true;
  s.position_mm = -12.25;
  s.frame.mode = homing::HomingMode::home_cam;
  s.frame.direction = homing::Direction::positive;
  s.frame.sensor_nc = true;
  s.frame.slave_of = 2;
  s.frame.slave_mode = homing::SlaveMode::external_commutator;
  s.frame.pull_off_mm = 1.5;
  s.frame.switch_compensation_mm = -0.25;
  s.frame.home_position_mm = 7.0;
  s.frame.cam_edge = homing::CamEdge::ahead;
  const homing::LastStops back = server::to_engine(server::to_store(stops));
  CHECK(back[3].frame == s.frame);
  CHECK(back[3].position_mm == s.position_mm);
  CHECK(back[3].clean);
}

TEST_CASE("the start's log offers a reference check to a lone switch axis and not to either side of a gantry pair") {
  test_support::TempDir dir{"runtime-test"};
  std::vector<persistence::SettingDefault> defaults;
  for (const auto& [name, value] : registers::persisted_defaults()) defaults.push_back({name, value});
  persistence::OpenReport report;
  auto store = persistence::SettingsStore::open(dir.file("settings.db"), defaults, report, persistence::StoreOptions{});
  REQUIRE(store);
  homing::Settings settings = default_settings();
  settings.axes[1].slave_of = 1;  // Y follows X; Z alone
  REQUIRE(homing::gantry_master(settings, 1) == 0);
  const homing::Settings motion = homing::motion_settings(settings);
  homing::LastStops stops{};
  for (std::size_t a : {0u, 1u, 2u}) {
    stops[a].clean = true;
    stops[a].position_mm = 10.0 + static_cast<double>(a);
    stops[a].frame = homing::home_frame(motion.axes[a]);
  }
  REQUIRE(store->record_last_stops(server::to_store(stops)));
  test_support::CapturedLog log;
  REQUIRE(server::take_last_stops(*store, settings));
  const std::string text = log.text();
  INFO(text);
  CHECK_THAT(text, Catch::Contains("last stop: X stopped cleanly at 10.000 mm: trust last_stop_clean (one side of a "
                                   "gantry pair cannot be checked alone: home the pair with a full cycle)"));
  CHECK_THAT(text, Catch::Contains("last stop: Y stopped cleanly at 11.000 mm: trust last_stop_clean (one side of a "
                                   "gantry pair cannot be checked alone"));
  CHECK_THAT(text, Catch::Contains("last stop: Z stopped cleanly at 12.000 mm: trust last_stop_clean; a reference "
                                   "check (cmd.refcheck, homingctl refcheck) may home it without a full cycle"));
}
