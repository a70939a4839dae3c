// What an axis is (axis.<a>.kind) names the unit of its values everywhere the
// engine writes one: a linear A (the second motor of a gantry) reads mm, a
// slave reads in its master's unit, X, Y and Z cannot be rotary.
#include <catch2/catch.hpp>

#include "homing/gantry.hpp"
#include "homing/settings_check.hpp"
#include "rig.hpp"

using namespace rig;

namespace {

constexpr std::size_t kY = 1, kA = 3;

// Y homes on its switch; A is the second motor of Y (software-slaved, its own
// sensor), set linear as a machine builder would.
Rig linear_a_slave_of_y() {
  Rig r;
  r.settings.axes[kY] = typical_axis();
  r.settings.axes[kA] = typical_axis();
  r.settings.axes[kA].slave_of = 2;  // Y
  r.settings.axes[kA].kind = AxisKind::linear;
  r.settings.axes[kA].max_misalignment_mm = 2;
  r.settings.global.sequence_steps = {axis_bit(kY), 0, 0, 0, 0, 0};
  return r;
}

}  // namespace

TEST_CASE("a new module's axes: X Y Z linear in mm, A B C rotary in degrees") {
  const Settings s;
  for (std::size_t a = 0; a < kAxisCount; ++a) {
    INFO("axis " << kAxisUpper[a]);
    CHECK(s.axes[a].kind == (a < 3 ? AxisKind::linear : AxisKind::rotary));
    CHECK(axis_unit(s, a) == (a < 3 ? "mm" : "deg"));
  }
}

SCENARIO("misalignment of a linear gantry slave on A reads in mm", "[alarms][gantry]") {
  Rig r = linear_a_slave_of_y();
  r.machine.axes[kA].actual_position_mm = 103;  // 3 mm behind the master
  r.pending.home_all = true;
  r.step();
  r.run_until([&] { return r.status().alarm || !r.status().homing; }, 60);
  REQUIRE(r.axis(kA).alarm.code == AlarmCode::misalignment);
  const std::string text = describe_alarm(kA, r.axis(kA).alarm, r.settings);
  INFO(text);
  CHECK_THAT(text, Catch::StartsWith("A: gantry stopped during seek: A (slave) did not find its home sensor, before "
                                      "racking by ") &&
                       Catch::Contains(" mm from square, more than max_misalignment 2 mm; the pair started the cycle square"));
  CHECK_THAT(text, !Catch::Contains("deg"));
}

TEST_CASE("a slave reads in its master's unit, whatever its own kind says") {
  Rig r = linear_a_slave_of_y();
  r.settings.axes[kA].kind = AxisKind::rotary;  // its own kind is not used while it is a slave
  CHECK(axis_kind(r.settings, kA) == AxisKind::linear);
  CHECK(axis_unit(r.settings, kA) == "mm");
  Alarm a{AlarmCode::misalignment};
  a.phase = Phase::seek;
  a.value = 2.5;
  CHECK_THAT(describe_alarm(kA, a, r.settings), Catch::Contains("racking by 2.500 mm from square, more than max_misalignment 2 mm"));
  // Once no longer a slave, A is what its own setting says.
  r.settings.axes[kA].slave_of = 0;
  CHECK(axis_unit(r.settings, kA) == "deg");
}

TEST_CASE("a settings fault of a linear gantry slave on A names mm") {
  Rig r = linear_a_slave_of_y();
  // A compensation that alone reaches max_misalignment: every homing would alarm.
  r.settings.axes[kA].switch_compensation_mm = 2.5;
  const auto fault = check_axis(r.settings, kA);
  REQUIRE(fault);
  CHECK(fault->rule == CheckRule::squaring_beyond_misalignment);
  const std::string text = describe_fault(*fault, r.settings);
  INFO(text);
  CHECK_THAT(text, Catch::Contains("is 2.5 mm, not less than axis.a.max_misalignment = 2 mm"));
  CHECK_THAT(text, !Catch::Contains("deg"));
  // The same fault as the alarm homing raises before any motion.
  Alarm alarm{fault->code()};
  alarm.field = fault->field;
  alarm.rule = static_cast<std::uint8_t>(fault->rule);
  alarm.value = fault->value;
  CHECK_THAT(describe_alarm(kA, alarm, r.settings), Catch::Contains("2.5 mm") && !Catch::Contains("deg"));
}

TEST_CASE("X, Y and Z cannot be rotary: the rule names the setting and what to do") {
  Settings s;
  s.axes[0] = typical_axis();
  s.axes[0].kind = AxisKind::rotary;
  const auto fault = check_axis(s, 0);
  REQUIRE(fault);
  CHECK(fault->rule == CheckRule::kind_linear_only);
  CHECK(fault->field == AxisField::kind);
  CHECK(describe_fault(*fault, s) ==
        "axis.x.kind = rotary: X is a linear axis (mm); only A, B and C can be rotary. Set axis.x.kind = linear, or "
        "put the rotary axis on A, B or C");
  // Refused whatever X does, even disabled.
  s.axes[0].mode = HomingMode::disabled;
  CHECK(check_axis(s, 0));
  // A, B and C may be either.
  for (std::size_t a = 3; a < kAxisCount; ++a) {
    s.axes[a].kind = AxisKind::rotary;
    CHECK_FALSE(check_axis(s, a));
    s.axes[a].kind = AxisKind::linear;
    CHECK_FALSE(check_axis(s, a));
  }
}
