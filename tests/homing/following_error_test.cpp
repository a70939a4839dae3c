// Hard-stop homing by following error (axis.<a>.stall_detect following_error):
// no switch and no stall input; the axis pushes into its mechanical stop at
// latch feedrate with reduced current until the encoder falls behind the
// steps by more than max_following_error. The stop is the reference, as with
// the stall input, and the push is bounded by max_seek_travel and
// stall_timeout_ms with the same alarms.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "homing/settings_check.hpp"
#include "rig.hpp"
#include "truth.hpp"

using namespace rig;

namespace {

constexpr double kResolution_mm = 0.001;  // the simulated encoder counts in 1 um

// X homes negative against its stop at -5 mm from 3 mm (8 mm away: 8 s at the
// latch feedrate of 60 mm/min), pull-off 1 mm, home position 0. Its encoder
// counts in 1 um with noise; the drive's stall output is dead, so only the
// encoder can tell the stop.
Rig following_error_rig() {
  Rig r;
  AxisSettings& s = r.settings.axes[0];
  s.mode = HomingMode::hard_stop;
  s.stall_detect = StallDetect::following_error;
  s.max_following_error_mm = 0.2;
  s.stall_timeout_ms = 20'000;
  sim::AxisConfig& c = r.machine.axes[0];
  c.actual_position_mm = 3;
  c.hard_stop_min_mm = -5;
  c.sensor_min_mm = 1;  // no switch is in the way: max below min
  c.sensor_max_mm = 0;
  c.absolute_offset_mm = 37;
  c.encoder_resolution_mm = kResolution_mm;
  c.encoder_noise_mm = 0.0003;
  c.fault = sim::Fault::stall_dead;
  return r;
}

// The push as the motor and the carriage made it.
struct Push {
  double motor_from = 0, motor_to = 0;  // motor position as it began and where it came to rest
  double carriage_from = 0, carriage_to = 0;
  bool seen = false;
  bool reduced_current = true;  // the push output was on in every period of the push
  double motor_travel() const { return std::abs(motor_to - motor_from); }
  double lost_mm() const { return motor_travel() - std::abs(carriage_to - carriage_from); }
};

void watch_push(Rig& r, Push& p) {
  r.on_period = [&p](Rig& rig) {
    if (rig.axis(0).phase != Phase::push_to_stop && !(p.seen && rig.axis(0).phase == Phase::stopping)) return;
    const double motor = rig.engine.outputs().axes[0].motor.position_mm;
    if (!p.seen) {
      p.seen = true;
      p.motor_from = motor;
      p.carriage_from = rig.actual(0);
    }
    p.motor_to = motor;
    p.carriage_to = rig.actual(0);
    p.reduced_current = p.reduced_current && rig.engine.outputs().axes[0].push_output;
  };
}

}  // namespace

SCENARIO("hard-stop homing by following error homes exactly at the stop, with no stall input",
         "[modes][hard_stop][following_error]") {
  Rig r = following_error_rig();
  Push push;
  watch_push(r, push);
  r.clear_trace();
  REQUIRE(r.home_all());
  CHECK_FALSE(r.status().alarm);
  CHECK(r.axis(0).homed);
  CHECK(r.saw(0, Phase::push_to_stop));
  CHECK(push.reduced_current);                                 // the whole push at reduced current
  CHECK(r.trace[0].min_actual == Approx(-5).margin(1e-9));     // it reached the stop and never passed it
  // Pull-off above the stop and home_position there, within the encoder's resolution.
  CHECK(r.actual(0) == Approx(-4).margin(kResolution_mm));
  CHECK(r.axis(0).position_mm == Approx(0).margin(kResolution_mm));
  // The motor ran on against the stop until the carriage lagged by the limit,
  // and no further than one period's travel and its braking beyond that.
  const AxisSettings& s = r.settings.axes[0];
  const double v = mm_per_min_to_mm_per_s(s.latch_feedrate_mm_per_min);
  CHECK(push.lost_mm() > s.max_following_error_mm - 2 * kResolution_mm);
  CHECK(push.lost_mm() < s.max_following_error_mm + v * r.dt_s + stop_distance_mm(v, s.acceleration_mm_per_s2) +
                             4 * kResolution_mm);
}

SCENARIO("hard-stop homing by following error: the encoder's noise moves the lost steps, never the home",
         "[modes][hard_stop][following_error]") {
  std::vector<double> lost;
  for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
    Rig r = following_error_rig();
    r.machine.seed = seed;
    r.machine.axes[0].encoder_resolution_mm = 0.002;
    r.machine.axes[0].encoder_noise_mm = 0.002;
    Push push;
    watch_push(r, push);
    REQUIRE(r.home_all());
    CHECK(r.actual(0) == Approx(-4).margin(1e-9));
    CHECK(r.axis(0).position_mm == Approx(0).margin(1e-9));
    lost.push_back(push.lost_mm());
  }
  // Different readings, different moments the limit is passed: the spread is real.
  CHECK(*std::max_element(lost.begin(), lost.end()) - *std::min_element(lost.begin(), lost.end()) > 1e-3);
}

SCENARIO("hard-stop homing by following error: a limit too large to reach within max_seek_travel is stop_not_found, "
         "and the motor pushes no further than that travel",
         "[modes][hard_stop][following_error][alarms]") {
  Rig r = following_error_rig();
  AxisSettings& s = r.settings.axes[0];
  s.max_seek_travel_mm = 9;       // the stop lies 8 mm away: 1 mm of steps lost against it at most
  s.max_following_error_mm = 2;   // more than that 1 mm: the carriage never lags by it
  REQUIRE_FALSE(check_axis(r.settings, 0));
  Push push;
  watch_push(r, push);
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::stop_not_found);
  CHECK(r.axis(0).alarm.phase == Phase::push_to_stop);
  CHECK(r.axis(0).alarm.value == Approx(9).margin(1e-6));
  CHECK_FALSE(r.axis(0).homed);
  CHECK(push.motor_travel() <= 9 + 1e-6);              // nothing moved past the push's distance
  CHECK(r.actual(0) == Approx(-5).margin(1e-9));       // against the stop, never through it
  const std::string text = describe_alarm(0, r.axis(0).alarm, r.settings);
  CHECK_THAT(text, Catch::Contains("within 9.000 mm of travel toward the mechanical stop"));
  CHECK_THAT(text, Catch::Contains("never fell behind its steps by more than max_following_error 2 mm"));
}

SCENARIO("hard-stop homing by following error: pushing longer than stall_timeout_ms is stall_timeout",
         "[modes][hard_stop][following_error][alarms]") {
  Rig r = following_error_rig();
  r.settings.axes[0].stall_timeout_ms = 2'000;  // 2 s at 1 mm/s: the stop is 8 mm away
  r.clear_trace();
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::stall_timeout);
  CHECK(r.axis(0).alarm.phase == Phase::push_to_stop);
  CHECK(r.trace[0].min_actual > -5 + 1);  // stopped well before the stop
  CHECK_THAT(describe_alarm(0, r.axis(0).alarm, r.settings), Catch::Contains("max_following_error 0.2 mm"));
}

SCENARIO("hard-stop homing by following error: an encoder without a valid position is encoder_fault and nothing moves",
         "[modes][hard_stop][following_error][alarms]") {
  Rig r = following_error_rig();
  r.tweak_inputs = [](Inputs& in) { in.axes[0].absolute_valid = false; };
  r.clear_trace();
  CHECK_FALSE(r.home_all());
  CHECK(r.axis(0).alarm.code == AlarmCode::encoder_fault);
  CHECK(r.axis(0).alarm.phase == Phase::push_to_stop);
  CHECK(r.trace[0].path_mm == 0);
  CHECK_FALSE(r.engine.outputs().axes[0].push_output);
}

SCENARIO("hard-stop homing by following error: an encoder lost during the push is encoder_fault, braking at reduced "
         "current",
         "[modes][hard_stop][following_error][alarms]") {
  Rig r = following_error_rig();
  bool lost = false;
  r.tweak_inputs = [&lost](Inputs& in) {
    if (lost) in.axes[0].absolute_valid = false;
  };
  r.pending.home_all = true;
  r.step();
  r.run_until([&] { return r.axis(0).phase == Phase::push_to_stop && r.axis(0).velocity_mm_per_s != 0; }, 5);
  r.run_for(1);
  lost = true;
  r.run_until([&] { return r.status().alarm; }, 1);
  CHECK(r.axis(0).alarm.code == AlarmCode::encoder_fault);
  CHECK(r.axis(0).alarm.phase == Phase::push_to_stop);
  CHECK(r.engine.outputs().axes[0].push_output);  // still braking: the current stays reduced
  r.run_until([&] { return !r.any_moving(); }, 5);
  CHECK_FALSE(r.engine.outputs().axes[0].push_output);
  CHECK(r.actual(0) > -5 + 1);
  CHECK_FALSE(r.axis(0).homed);
}

SCENARIO("hard-stop homing by following error: the stall input is not read, stuck on or dead",
         "[modes][hard_stop][following_error]") {
  for (const sim::Fault f : {sim::Fault::stall_stuck, sim::Fault::stall_dead}) {
    DYNAMIC_SECTION(name_of(f)) {
      Rig r = following_error_rig();
      r.machine.axes[0].fault = f;
      REQUIRE(r.home_all());
      CHECK(r.actual(0) == Approx(-4).margin(kResolution_mm));
    }
  }
}

TEST_CASE("hard-stop homing by following error needs a limit above the encoder's noise and within the push's travel",
          "[modes][hard_stop][following_error][rules]") {
  Settings s;
  s.axes[0] = typical_axis();  // latch 60 mm/min: 1 mm/s
  s.axes[0].mode = HomingMode::hard_stop;
  s.axes[0].stall_detect = StallDetect::following_error;
  REQUIRE_FALSE(check_axis(s, 0));
  const double floor = following_error_floor_mm(s.axes[0]);
  CHECK(floor == Approx(10 * kEncoderReadingError_mm + 1.0 * kBrakingHorizon_s));
  SECTION("a limit of 0 is refused") {
    s.axes[0].max_following_error_mm = 0;
    const auto f = check_axis(s, 0);
    REQUIRE(f);
    CHECK(f->field == AxisField::max_following_error);
    CHECK(f->rule == CheckRule::not_positive);
  }
  SECTION("a limit within the encoder's resolution and noise and the lag of a moving axis is refused") {
    s.axes[0].max_following_error_mm = floor;
    const auto f = check_axis(s, 0);
    REQUIRE(f);
    CHECK(f->field == AxisField::max_following_error);
    CHECK(f->rule == CheckRule::following_error_in_noise);
    CHECK(f->value == Approx(floor));
    CHECK_THAT(describe_fault(*f, s), Catch::Contains("axis.x.max_following_error = 0.04 mm does not exceed 0.040 mm"));
    s.axes[0].max_following_error_mm = floor + 0.001;
    CHECK_FALSE(check_axis(s, 0));
  }
  SECTION("a faster latch feedrate lags more while it moves, and needs a larger limit") {
    s.axes[0].max_following_error_mm = 0.05;
    CHECK_FALSE(check_axis(s, 0));
    s.axes[0].latch_feedrate_mm_per_min = 600;  // 10 mm/s: 0.2 mm in a 20 ms period
    const auto f = check_axis(s, 0);
    REQUIRE(f);
    CHECK(f->rule == CheckRule::following_error_in_noise);
  }
  SECTION("a limit the push can never reach within max_seek_travel is refused") {
    s.axes[0].max_following_error_mm = s.axes[0].max_seek_travel_mm;
    const auto f = check_axis(s, 0);
    REQUIRE(f);
    CHECK(f->rule == CheckRule::following_error_beyond_travel);
    CHECK_THAT(describe_fault(*f, s), Catch::Contains("is not shorter than axis.x.max_seek_travel = 300 mm"));
  }
  SECTION("with the stall input, the limit is not used") {
    s.axes[0].stall_detect = StallDetect::stall_input;
    s.axes[0].max_following_error_mm = 0;
    CHECK_FALSE(check_axis(s, 0));
  }
  SECTION("nor on an axis that does not push to a stop") {
    s.axes[0].mode = HomingMode::switch_release;
    s.axes[0].max_following_error_mm = 0;
    CHECK_FALSE(check_axis(s, 0));
  }
}

TEST_CASE("the hard-stop row needs the stall input or the encoder, as the axis's stall_detect chooses",
          "[modes][hard_stop][following_error][table]") {
  AxisSettings s = typical_axis();
  s.mode = HomingMode::hard_stop;
  CHECK(needs_signal(s, Signal::stall));
  CHECK_FALSE(needs_signal(s, Signal::absolute_encoder));
  CHECK(needs_signal(s, Signal::push_output));
  s.stall_detect = StallDetect::following_error;
  CHECK_FALSE(needs_signal(s, Signal::stall));
  CHECK(needs_signal(s, Signal::absolute_encoder));
  CHECK(needs_signal(s, Signal::push_output));
  // Every other method needs the same whatever stall_detect says.
  for (const ModeRow& row : kModeTable) {
    if (row.detects_stop()) continue;
    AxisSettings o = typical_axis();
    o.mode = row.value;
    const Signals by_stall = signals_needed(o);
    o.stall_detect = StallDetect::following_error;
    CHECK(signals_needed(o) == by_stall);
    CHECK(by_stall == row.needs);
  }
}

SCENARIO("hard-stop homing by following error: a reversed encoder on a carriage already near the stop homes on the "
         "stop, the travel counted as lag",
         "[modes][hard_stop][following_error]") {
  // Campaign seed 2258828930: 0.3 mm from the stop with a 2 mm limit, the
  // carriage reaches the stop before it has moved the quarter of the limit
  // that shows a reversal; its 0.3 mm then count twice against the steps.
  Rig r = following_error_rig();
  r.settings.axes[0].max_following_error_mm = 2;
  r.machine.axes[0].actual_position_mm = -4.7;
  r.machine.axes[0].fault = sim::Fault::encoder_reversed;
  Push push;
  watch_push(r, push);
  REQUIRE(r.home_all());
  CHECK(r.trace[0].min_actual == Approx(-5).margin(1e-9));
  CHECK(r.actual(0) == Approx(-4).margin(kResolution_mm));
  CHECK(r.axis(0).position_mm == Approx(0).margin(kResolution_mm));
  // Told after the limit less the gap of steps, not the limit plus the gap.
  CHECK(push.motor_travel() > 2 - 0.3 - 2 * kResolution_mm);
  CHECK(push.motor_travel() < 2 - 0.3 + 0.05);
}
