// The log lines of a settings change that costs axes their reference (server/frame_changes.hpp).
#include <catch2/catch.hpp>

#include <map>

#include "registers/defaults.hpp"
#include "homing/gantry.hpp"
#include "server/frame_changes.hpp"

namespace {

homing::Settings default_settings() {
  std::map<std::string, std::int64_t> raw;
  for (const auto& [name, value] : registers::persisted_defaults()) raw[name] = value;
  return registers::settings_from_raw(raw).settings;
}

}  // namespace

TEST_CASE("a home position changed on a homed axis is one line naming the axis the setting and the way back") {
  const homing::Settings before = default_settings();
  homing::Settings after = before;
  after.axes[0].home_position_mm += 1.0;
  homing::Status status{};
  status.axes[0].trust = homing::Trust::homed_this_power_on;
  status.axes[1].trust = homing::Trust::homed_this_power_on;  // its frame did not change
  const auto lines = server::references_lost(before, after, status);
  REQUIRE(lines.size() == 1);
  CHECK(lines[0] ==
        "axis x is no longer homed: home_position changed, which places its coordinates; home it again before "
        "moving it by coordinates");
}

TEST_CASE("a frame change withdraws a clean stop's reference check offer and says a full cycle is needed") {
  const homing::Settings before = default_settings();
  homing::Settings after = before;
  after.axes[2].pull_off_mm += 0.5;
  after.axes[2].sensor_nc = !after.axes[2].sensor_nc;
  homing::Status status{};
  status.axes[2].trust = homing::Trust::last_stop_clean;
  const auto lines = server::references_lost(before, after, status);
  REQUIRE(lines.size() == 1);
  CHECK(lines[0] ==
        "axis z: the reference check its clean stop offered is withdrawn: sensor_nc, pull_off changed, which places "
        "its coordinates; home it with a full cycle");
}

TEST_CASE("a frame change of an axis with nothing to lose and a change that places nothing are not logged") {
  const homing::Settings before = default_settings();
  homing::Settings after = before;
  after.axes[0].home_position_mm += 1.0;          // X: unknown trust, nothing lost
  after.axes[1].seek_feedrate_mm_per_min += 100;  // Y homed: not in its frame
  homing::Status status{};
  status.axes[0].trust = homing::Trust::unknown;
  status.axes[1].trust = homing::Trust::reference_checked;
  CHECK(server::references_lost(before, after, status).empty());
}

TEST_CASE("a gantry slave's own switch compensation changed unhomes the pair and the master's line names the slave") {
  homing::Settings before = default_settings();
  before.axes[1] = before.axes[0];
  before.axes[1].slave_of = 1;  // Y follows X
  REQUIRE(homing::gantry_master(before, 1) == 0);
  homing::Settings after = before;
  after.axes[1].switch_compensation_mm += 0.3;
  homing::Status status{};
  status.axes[0].trust = homing::Trust::homed_this_power_on;
  status.axes[1].trust = homing::Trust::homed_this_power_on;
  const auto lines = server::references_lost(before, after, status);
  REQUIRE(lines.size() == 2);
  CHECK(lines[0] ==
        "axis x is no longer homed: its gantry partner y lost its reference (switch_compensation of y changed), and a "
        "pair shares one; home it again before moving it by coordinates");
  CHECK(lines[1] ==
        "axis y is no longer homed: switch_compensation changed, which places its coordinates; home it again before "
        "moving it by coordinates");
  // The master's home position, which its slave moves with.
  after = before;
  after.axes[0].home_position_mm += 1.0;
  const auto by_master = server::references_lost(before, after, status);
  REQUIRE(by_master.size() == 2);
  CHECK(by_master[0] ==
        "axis x is no longer homed: home_position changed, which places its coordinates; home it again before moving "
        "it by coordinates");
  CHECK(by_master[1] ==
        "axis y is no longer homed: home_position of its gantry master x changed, which places its coordinates; home "
        "it again before moving it by coordinates");
}

TEST_CASE("a gantry partner is named only when the changed side was homed and the partner is too, as the engine unhomes") {
  homing::Settings before = default_settings();
  before.axes[1] = before.axes[0];
  before.axes[1].slave_of = 1;  // Y follows X
  homing::Settings after = before;
  after.axes[1].switch_compensation_mm += 0.3;
  homing::Status status{};
  status.axes[0].trust = homing::Trust::homed_this_power_on;  // X homed, Y lost its reference before (a drive fault)
  status.axes[1].trust = homing::Trust::unknown;
  CHECK(server::references_lost(before, after, status).empty());
  status.axes[0].trust = homing::Trust::last_stop_clean;  // after a restart: offers stay with each side's own frame
  status.axes[1].trust = homing::Trust::last_stop_clean;
  const auto lines = server::references_lost(before, after, status);
  REQUIRE(lines.size() == 1);
  CHECK(lines[0].rfind("axis y: the reference check its clean stop offered is withdrawn", 0) == 0);
}
