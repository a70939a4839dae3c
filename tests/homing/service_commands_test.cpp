// Service commands of the engine: unhoming an axis without moving it (with
// its gantry partner), refused while anything of it moves; and a machine that
// may only be homed as a whole (global.single_axis_homing off).
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

#include "rig.hpp"

using namespace rig;

namespace {
constexpr std::size_t X = 0, Y = 1, Z = 2, B = 4;

void unhome(Rig& r, AxisMask axes) {
  r.pending.unhome_axes = axes;
  r.step();
}
}  // namespace

SCENARIO("unhoming an axis forgets its reference without moving anything", "[service]") {
  Rig r;
  r.add_axis(Y, 2);
  REQUIRE(r.home_all());
  const auto before = r.status().command_count;
  const double x_at = r.actual(X);
  unhome(r, axis_bit(X));
  CHECK(r.status().last_command_result == CommandResult::accepted);
  CHECK(r.status().command_count == before + 1);
  CHECK_FALSE(r.axis(X).homed);
  CHECK(r.axis(Y).homed);  // the others keep theirs
  CHECK(r.status().state != MachineState::homed);
  r.run_for(0.2);
  CHECK(r.actual(X) == x_at);
  CHECK_FALSE(r.any_moving());
  // Homing it again gives it back its reference.
  REQUIRE(r.home_axes(axis_bit(X)));
  CHECK(r.axis(X).homed);
}

SCENARIO("unhoming one side of a gantry unhomes both sides", "[service][gantry]") {
  Rig r;
  r.settings.axes[B] = typical_axis();
  r.settings.axes[B].slave_of = static_cast<std::uint8_t>(Y + 1);
  r.add_axis(Y, 2);
  REQUIRE(r.home_all());
  REQUIRE(r.axis(Y).homed);
  REQUIRE(r.axis(B).homed);
  unhome(r, axis_bit(B));
  CHECK(r.status().last_command_result == CommandResult::accepted);
  CHECK_FALSE(r.axis(Y).homed);
  CHECK_FALSE(r.axis(B).homed);
}

SCENARIO("unhoming is refused busy while the axis jogs or a cycle runs, and changes nothing", "[service]") {
  Rig r;
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  REQUIRE(r.home_all());
  r.jog(X, +1);
  REQUIRE(r.run_until([&] { return r.any_moving(); }, 1));
  unhome(r, axis_bit(X));
  CHECK(r.status().last_command_result == CommandResult::refused_busy);
  CHECK(r.axis(X).homed);
  r.release_jogs();
  REQUIRE(r.run_until([&] { return !r.any_moving(); }, 5));
  r.pending.home_all = true;
  r.step();
  REQUIRE(r.status().homing);
  unhome(r, axis_bit(Z));
  CHECK(r.status().last_command_result == CommandResult::refused_busy);
  CHECK(r.status().homing);
}

SCENARIO("with single-axis homing off only home-all homes: a single-axis home is refused and moves nothing",
         "[service]") {
  Rig r;
  r.settings.global.single_axis_homing = false;
  r.step();
  const double x_at = r.actual(X);
  r.home_axes(axis_bit(X));
  CHECK(r.status().last_command_result == CommandResult::refused_home_all_only);
  CHECK(r.actual(X) == x_at);
  CHECK_FALSE(r.axis(X).homed);
  CHECK(r.home_all());
  CHECK(r.axis(X).homed);
}

SCENARIO("an axis's own allowed_without_homing overrides the global one, each way", "[service]") {
  Rig r;
  r.add_axis(Z, 1);
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::jog_reduced;
  r.settings.axes[Z].allowed_without_homing = AxisAllowedWithoutHoming::none;  // over the work
  r.settings.axes[X].allowed_without_homing = AxisAllowedWithoutHoming::all;
  r.step();
  REQUIRE_FALSE(r.axis(X).homed);
  REQUIRE_FALSE(r.axis(Z).homed);
  CHECK((r.status().interlocks & interlock::not_homed) != 0);
  // Z: nothing moves before homing, not even a slow jog.
  const double z_at = r.actual(Z);
  r.jog(Z, +1);
  r.run_for(0.2);
  CHECK(r.status().last_command_result == CommandResult::refused_not_homed);
  CHECK(r.actual(Z) == z_at);
  r.release_jogs();
  r.step();
  // X: a move is allowed before homing, at its jog feedrate.
  const double x_at = r.actual(X);
  r.move(X, r.axis(X).position_mm + 5);
  CHECK(r.status().last_command_result == CommandResult::accepted);
  REQUIRE(r.run_until([&] { return !r.any_moving(); }, 30));
  CHECK(r.actual(X) == Approx(x_at + 5).margin(1e-6));
  // With X and Z both 'all', nothing is limited until homing.
  r.settings.axes[Z].allowed_without_homing = AxisAllowedWithoutHoming::all;
  r.step();
  CHECK((r.status().interlocks & interlock::not_homed) == 0);
}

namespace {
void set_position(Rig& r, std::size_t axis, double mm) {
  r.pending.set_position_axes = axis_bit(axis);
  r.pending.set_position_mm[axis] = mm;
  r.step();
}
}  // namespace

SCENARIO("setting an unhomed axis's position gives it that coordinate where it stands, without moving, still "
         "unhomed",
         "[service]") {
  Rig r;
  r.step();
  const double x_at = r.actual(X);
  const auto sets = r.axis(X).positions_set;
  const std::uint32_t before = r.status().command_count;
  set_position(r, X, 42.5);
  CHECK(r.status().last_command_result == CommandResult::accepted);
  CHECK(r.status().command_count == before + 1);
  CHECK(r.axis(X).position_mm == Approx(42.5).margin(1e-9));
  CHECK(r.axis(X).positions_set == sets + 1);
  CHECK_FALSE(r.axis(X).homed);  // the technician's word, not a reference
  r.run_for(0.2);
  CHECK(r.actual(X) == x_at);
  CHECK_FALSE(r.any_moving());
  // A jog then counts from the coordinate set (allowed without homing here).
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.jog(X, +1);
  r.run_for(0.3);
  r.release_jogs();
  REQUIRE(r.run_until([&] { return !r.any_moving(); }, 2));
  CHECK(r.axis(X).position_mm - 42.5 == Approx(r.actual(X) - x_at).margin(1e-6));
}

SCENARIO("setting the position of a homed axis is refused_homed and changes nothing", "[service]") {
  Rig r;
  REQUIRE(r.home_all());
  const double at = r.axis(X).position_mm;
  const auto sets = r.axis(X).positions_set;
  set_position(r, X, 100);
  CHECK(r.status().last_command_result == CommandResult::refused_homed);
  CHECK(r.axis(X).position_mm == at);
  CHECK(r.axis(X).homed);
  CHECK(r.axis(X).positions_set == sets);
  // Unhomed first, it is taken.
  unhome(r, axis_bit(X));
  set_position(r, X, 100);
  CHECK(r.status().last_command_result == CommandResult::accepted);
  CHECK(r.axis(X).position_mm == Approx(100).margin(1e-9));
}

SCENARIO("setting the position is refused busy while the axis jogs, refused for a bad number, and changes nothing",
         "[service]") {
  Rig r;
  r.settings.global.allowed_without_homing = AllowedWithoutHoming::all;
  r.step();
  set_position(r, X, std::numeric_limits<double>::quiet_NaN());
  CHECK(r.status().last_command_result == CommandResult::refused_invalid);
  r.jog(X, +1);
  REQUIRE(r.run_until([&] { return r.any_moving(); }, 1));
  const double believed = r.axis(X).position_mm;
  set_position(r, X, 7);
  CHECK(r.status().last_command_result == CommandResult::refused_busy);
  CHECK(std::abs(r.axis(X).position_mm - 7) > 0.5);
  CHECK(std::abs(r.axis(X).position_mm - believed) < 0.1);  // went on counting from where it was
}

SCENARIO("a gantry's position is set through its master, both sides taking it, and refused on the slave",
         "[service][gantry]") {
  Rig r;
  r.settings.axes[B] = typical_axis();
  r.settings.axes[B].slave_of = static_cast<std::uint8_t>(Y + 1);
  r.add_axis(Y, 2);
  r.step();
  set_position(r, B, 5);
  CHECK(r.status().last_command_result == CommandResult::refused_slave_axis);
  set_position(r, Y, 5);
  CHECK(r.status().last_command_result == CommandResult::accepted);
  CHECK(r.axis(Y).position_mm == Approx(5).margin(1e-9));
  CHECK(r.axis(B).position_mm == Approx(5).margin(1e-9));
  CHECK_FALSE(r.axis(Y).homed);
  CHECK_FALSE(r.axis(B).homed);
}
