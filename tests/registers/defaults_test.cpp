// The default column is the only source of defaults; they must home.
#include <catch2/catch.hpp>

#include "homing/settings_check.hpp"
#include "registers/defaults.hpp"
#include "registers/lookup.hpp"

using namespace registers;

TEST_CASE("default settings pass the engine's check on every axis, even with every axis enabled") {
  auto s = default_settings();
  for (std::size_t axis = 0; axis < homing::kAxisCount; ++axis) {
    const auto fault = homing::check_axis(s, axis);
    INFO((fault ? homing::describe_fault(*fault, s) : std::string{}));
    CHECK_FALSE(fault);
  }
  for (auto& a : s.axes) a.mode = homing::HomingMode::switch_reapproach;
  for (std::size_t axis = 0; axis < homing::kAxisCount; ++axis) CHECK_FALSE(homing::check_axis(s, axis));
}

TEST_CASE("product defaults: X Y Z home on a switch, A B C disabled, Z first then X and Y") {
  const auto s = default_settings();
  CHECK(s.axes[0].mode == homing::HomingMode::switch_release);
  CHECK(s.axes[2].mode == homing::HomingMode::switch_release);
  CHECK(s.axes[3].mode == homing::HomingMode::disabled);
  CHECK(s.axes[0].seek_feedrate_mm_per_min == 1000);
  CHECK(s.axes[0].latch_feedrate_mm_per_min == 100);
  CHECK(s.axes[0].max_stop_distance_mm == 10);
  CHECK(s.axes[0].soft_limit_min_mm == -1000);
  CHECK(s.global.sequence_steps[0] == 4);
  CHECK(s.global.sequence_steps[1] == 3);
  CHECK(s.global.alarm_clears_homed);
}

TEST_CASE("a new module allows only a reduced-speed jog before homing, in the table and in the engine alike") {
  CHECK(default_settings().global.allowed_without_homing == homing::AllowedWithoutHoming::jog_reduced);
  CHECK(default_settings().global.allowed_without_homing == homing::GlobalSettings{}.allowed_without_homing);
  CHECK(find_register("global.allowed_without_homing")->default_raw ==
        static_cast<std::int64_t>(homing::AllowedWithoutHoming::jog_reduced));
}

TEST_CASE("a new module's failure policy stops every axis, in the table and in the engine alike") {
  CHECK(default_settings().global.failure_policy == homing::FailurePolicy::stop_all);
  CHECK(homing::GlobalSettings{}.failure_policy == homing::FailurePolicy::stop_all);
  const Register* r = find_register("global.failure_policy");
  REQUIRE(r);
  CHECK(r->address == 61);
  CHECK(r->default_raw == static_cast<std::int64_t>(homing::FailurePolicy::stop_all));
}

TEST_CASE("persisted defaults hold every persisted register and no runtime value") {
  const auto rows = persisted_defaults();
  // 6 sequence steps + 11 global settings (single_axis_homing the sixth, then trend_cycles,
  // trend_growth_pct and trend_min_change of the health trend, failure_policy, edit_timeout_s), 42 settings per axis (30, plus
  // indexer_lock and lock_timeout_ms of the locking indexer, allowed_without_homing, limits_fitted,
  // limits_nc, cam_edge and limit_overtravel, latch_passes, max_latch_spread, max_skew_change,
  // stall_detect and max_following_error, refcheck_tolerance of the reference check, global failure_policy)
  CHECK(rows.size() == 6 + 11 + 43 * homing::kAxisCount);
  for (const auto& [name, raw] : rows) {
    const Register* r = find_register(name);
    REQUIRE(r);
    CHECK(r->persisted);
    CHECK(raw == r->default_raw);
    CHECK(name != "host.heartbeat");
    CHECK(name.find(".target") == std::string::npos);
  }
}

TEST_CASE("settings survive settings_to_raw and settings_from_raw") {
  auto s = default_settings();
  s.axes[1].home_position_mm = -12.5;
  s.axes[4].mode = homing::HomingMode::pushing_reapproach;
  s.axes[5].slave_of = 4;
  s.global.watchdog_ms = 250;
  const auto raw = settings_to_raw(s);
  CHECK(raw.at("axis.y.home_position") == -12500);
  const auto back = settings_from_raw(raw);
  CHECK(back.complete());
  CHECK(back.unknown.empty());
  CHECK(settings_to_raw(back.settings) == raw);
}

TEST_CASE("stored rows that are missing, out of range or unknown are reported, defaults used") {
  auto raw = settings_to_raw(default_settings());
  raw.erase("axis.x.pull_off");
  raw["axis.y.seek_feedrate"] = 90000;
  raw["axis.x.retired_setting"] = 3;
  const auto back = settings_from_raw(raw);
  CHECK_FALSE(back.complete());
  CHECK(back.defaulted == std::vector<std::string>{"axis.x.pull_off"});
  REQUIRE(back.rejected.size() == 1);
  CHECK_THAT(back.rejected[0], Catch::Contains("axis.y.seek_feedrate"));
  CHECK(back.unknown == std::vector<std::string>{"axis.x.retired_setting"});
  CHECK(back.settings.axes[1].seek_feedrate_mm_per_min == 1000);
}
