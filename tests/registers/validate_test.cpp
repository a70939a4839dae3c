// Writes are all or nothing: addressing faults are 02, values and setting
// combinations that cannot work are 03, and nothing is applied on a refusal.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <vector>

#include "homing/gantry.hpp"
#include "registers/defaults.hpp"
#include "registers/lookup.hpp"
#include "registers/validate.hpp"
#include "tests/support/named_registers.hpp"

using namespace registers;

namespace {
using test_support::reg;  // throws, naming the register, when the table has none

std::vector<std::uint16_t> words_of(const Register& r, std::int64_t raw, WordOrder order = WordOrder::high_first) {
  std::vector<std::uint16_t> w(r.words());
  encode_words(r, raw, order, w);
  return w;
}

auto write_one(const char* name, std::int64_t raw, const homing::Settings& s,
               WordOrder order = WordOrder::high_first) {
  const Register& r = reg(name);
  return validate_write(r.table, r.address, words_of(r, raw, order), order, s, default_host_registers());
}
}  // namespace

TEST_CASE("GIVEN defaults WHEN a setting is written in range THEN the copy changes and the change is listed") {
  const auto s = default_settings();
  const auto ok = write_one("axis.x.pull_off", 2500, s);
  REQUIRE(ok);
  CHECK(ok->settings.axes[0].pull_off_mm == 2.5);
  REQUIRE(ok->changes.size() == 1);
  CHECK(ok->changes[0].reg->name() == "axis.x.pull_off");
  CHECK(ok->changes[0].old_raw == 1000);
  CHECK(ok->changes[0].new_raw == 2500);
  CHECK(ok->changes_persisted());
}

TEST_CASE("a 32-bit write decodes with the low-first word order too") {
  const auto ok = write_one("axis.x.home_position", -7250, default_settings(), WordOrder::low_first);
  REQUIRE(ok);
  CHECK(ok->settings.axes[0].home_position_mm == -7.25);
}

TEST_CASE("a write out of range is exception 03 and changes nothing") {
  const auto s = default_settings();
  const auto refused = write_one("axis.x.seek_feedrate", 60001, s);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ExceptionCode::illegal_data_value);
  CHECK_THAT(refused.error().message, Catch::Contains("axis.x.seek_feedrate") && Catch::Contains("60000"));
  // The first number past the mode table's last row.
  const auto mode = write_one("axis.y.mode", homing::kHomingModeCount, s);
  REQUIRE_FALSE(mode);
  CHECK(mode.error().code == ExceptionCode::illegal_data_value);
}

TEST_CASE("a write to a read-only register is exception 02") {
  const Register& pos = reg("axis.x.position");
  const std::array<std::uint16_t, 2> w{0, 5};
  const auto refused = validate_write(Table::input_register, pos.address, w, WordOrder::high_first,
                                      default_settings(), default_host_registers());
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ExceptionCode::illegal_data_address);
  CHECK_THAT(refused.error().message, Catch::Contains("read-only"));
}

TEST_CASE("a write covering only one half of a 32-bit value is exception 02") {
  const Register& travel = reg("axis.x.max_seek_travel");
  const std::array<std::uint16_t, 1> one{7};
  const auto s = default_settings();
  const auto h = default_host_registers();
  const auto first_half = validate_write(Table::holding_register, travel.address, one, WordOrder::high_first, s, h);
  REQUIRE_FALSE(first_half);
  CHECK(first_half.error().code == ExceptionCode::illegal_data_address);
  const auto second_half =
      validate_write(Table::holding_register, travel.address + 1, one, WordOrder::high_first, s, h);
  REQUIRE_FALSE(second_half);
  CHECK(second_half.error().code == ExceptionCode::illegal_data_address);
  CHECK_THAT(second_half.error().message, Catch::Contains("axis.x.max_seek_travel"));
}

TEST_CASE("an unmapped address inside a write range is exception 02") {
  // sequence.step6 at 5, then a gap until global.allowed_without_homing at 10
  const std::array<std::uint16_t, 3> w{0, 0, 0};
  const auto refused = validate_write(Table::holding_register, 4, w, WordOrder::high_first, default_settings(),
                                      default_host_registers());
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ExceptionCode::illegal_data_address);
  CHECK_THAT(refused.error().message, Catch::Contains("6"));
}

TEST_CASE("a seek feedrate too fast to stop within max_stop_distance is 03 naming the setting, nothing applied") {
  // 1000 mm/s² and 10 mm: v²/2a > 10 mm from v = 141 mm/s = 8485 mm/min
  const auto s = default_settings();
  const auto refused = write_one("axis.x.seek_feedrate", 20000, s);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ExceptionCode::illegal_data_value);
  CHECK_THAT(refused.error().message, Catch::Contains("axis.x.max_stop_distance") && Catch::Contains("seek_feedrate"));
}

TEST_CASE("the cross-field check is skipped on a disabled axis") {
  const auto s = default_settings();
  REQUIRE(s.axes[3].mode == homing::HomingMode::disabled);
  CHECK(write_one("axis.a.seek_feedrate", 20000, s));
}

TEST_CASE("a multi-register write is all or nothing") {
  const auto s = default_settings();
  const auto h = default_host_registers();
  // seek_feedrate (+2), latch_feedrate (+3), acceleration (+4) of X in one FC 16
  const Register& seek = reg("axis.x.seek_feedrate");
  SECTION("one bad value refuses the whole request") {
    const std::array<std::uint16_t, 3> w{2000, 0, 800};  // latch 0 is out of range
    const auto refused = validate_write(Table::holding_register, seek.address, w, WordOrder::high_first, s, h);
    REQUIRE_FALSE(refused);
    CHECK(refused.error().code == ExceptionCode::illegal_data_value);
    CHECK_THAT(refused.error().message, Catch::Contains("axis.x.latch_feedrate"));
  }
  SECTION("values that only work together are accepted together") {
    // Faster seek needs more acceleration: 6000 mm/min at 5000 mm/s² stops in 1 mm.
    const std::array<std::uint16_t, 3> w{6000, 200, 5000};
    const auto ok = validate_write(Table::holding_register, seek.address, w, WordOrder::high_first, s, h);
    REQUIRE(ok);
    CHECK(ok->changes.size() == 3);
    CHECK(ok->settings.axes[0].acceleration_mm_per_s2 == 5000);
    // ...and the same seek alone is refused, leaving the caller's settings as they were.
    CHECK_FALSE(write_one("axis.x.seek_feedrate", 20000, s));
    CHECK(s.axes[0].seek_feedrate_mm_per_min == 1000);
  }
}

TEST_CASE("host registers bypass the settings and coils give commands") {
  const auto s = default_settings();
  const auto hb = write_one("host.heartbeat", 42, s);
  REQUIRE(hb);
  CHECK(hb->host.heartbeat == 42);
  CHECK_FALSE(hb->changes_persisted());
  const auto target = write_one("axis.z.target", -2500, s);
  REQUIRE(target);
  CHECK(target->host.target_mm[2] == -2.5);

  const Register& home_x = reg("cmd.home.x");
  const std::array<std::uint16_t, 3> bits{1, 1, 0};  // home.x, jog_plus.x on, jog_minus.x off
  const auto ok = validate_write(Table::coil, home_x.address, bits, WordOrder::high_first, s, default_host_registers());
  REQUIRE(ok);
  REQUIRE(ok->commands.size() == 3);
  CHECK(ok->commands[0] == CommandRequest{Command::home_axis, 0, true});
  CHECK(ok->commands[1] == CommandRequest{Command::jog_plus, 0, true});
  CHECK(ok->commands[2] == CommandRequest{Command::jog_minus, 0, false});
  // The jog coils read back who holds them (the runtime's), not the value written.
  CHECK_FALSE(ok->host.jog_plus[0]);
}

TEST_CASE("a write of 0 to a pulse command coil commands nothing") {
  const Register& abort = reg("cmd.abort");
  const std::array<std::uint16_t, 1> zero{0};
  const auto ok = validate_write(Table::coil, abort.address, zero, WordOrder::high_first, default_settings(),
                                 default_host_registers());
  REQUIRE(ok);
  CHECK(ok->commands.empty());
}

TEST_CASE("a write to an unmapped coil is exception 02") {
  const std::array<std::uint16_t, 1> one{1};
  const auto refused = validate_write(Table::coil, 50, one, WordOrder::high_first, default_settings(),
                                      default_host_registers());
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ExceptionCode::illegal_data_address);
}

TEST_CASE("making an axis a slave checks it against its master") {
  auto s = default_settings();
  // Y slave of A: A is disabled, so it cannot be a master.
  const auto refused = write_one("axis.y.slave_of", 4, s);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ExceptionCode::illegal_data_value);
  CHECK_THAT(refused.error().message, Catch::Contains("axis.y.slave_of"));
  CHECK(write_one("axis.y.slave_of", 1, s));  // slave of X, which homes on a switch
}

// The gantry and limit rules of the engine's one rule set, refused at write time.
namespace {
homing::Settings with_x_y_homing() {
  homing::Settings s = default_settings();
  s.axes[0].mode = homing::HomingMode::switch_release;
  s.axes[1].mode = homing::HomingMode::switch_release;
  return s;
}
void refused_naming(const std::expected<AcceptedWrite, Refusal>& w, const char* words) {
  REQUIRE_FALSE(w);
  CHECK(w.error().code == ExceptionCode::illegal_data_value);
  CHECK_THAT(w.error().message, Catch::Contains(words) && Catch::Contains("nothing was written"));
}
}  // namespace

TEST_CASE("a disabled axis named as a slave, or as a master, is refused at write time") {
  homing::Settings s = with_x_y_homing();
  s.axes[1].mode = homing::HomingMode::disabled;
  refused_naming(write_one("axis.y.slave_of", 1, s), "disabled axis");
  s = with_x_y_homing();
  s.axes[1].slave_of = 1;
  refused_naming(write_one("axis.x.mode", 0, s), "disabled axis");
  refused_naming(write_one("axis.y.mode", 0, s), "disabled axis");
}

TEST_CASE("a slave of a slave is refused at write time") {
  homing::Settings s = with_x_y_homing();
  s.axes[2].mode = homing::HomingMode::switch_release;
  s.axes[1].slave_of = 1;
  refused_naming(write_one("axis.z.slave_of", 2, s), "itself a slave");
}

TEST_CASE("a gantry slave's own value of a setting it takes from its master is refused, naming the master's") {
  homing::Settings s = with_x_y_homing();
  s.axes[1].slave_of = 1;  // Y, software-slaved to X
  for (const char* name : {"axis.y.seek_feedrate", "axis.y.direction", "axis.y.latch_feedrate", "axis.y.home_position",
                           "axis.y.soft_limit_max", "axis.y.kind"}) {
    INFO(name);
    const Register& r = reg(name);
    const auto refused = write_one(name, r.default_raw == r.max ? r.min : r.max, s);
    REQUIRE_FALSE(refused);
    CHECK(refused.error().code == ExceptionCode::illegal_data_value);
    CHECK(refused.error().reason == RefusalReason::slave_inherits);
    const std::string on_master = "axis.x." + std::string(name).substr(7);
    CHECK(refused.error().address == reg(on_master.c_str()).address);  // status.last_refused_register: where to write it
    CHECK_THAT(refused.error().message, Catch::Contains("Y is a gantry slave of X") &&
                                            Catch::Contains("write " + on_master + " instead") &&
                                            Catch::Contains("nothing was written"));
  }
  THEN("its own settings are taken: sensor, pull-off, compensation, misalignment, acceleration") {
    CHECK(write_one("axis.y.sensor_nc", 1, s));
    CHECK(write_one("axis.y.pull_off", 1500, s));
    CHECK(write_one("axis.y.switch_compensation", -300, s));
    CHECK(write_one("axis.y.max_misalignment", 1500, s));
    CHECK(write_one("axis.y.debounce_ms", 3, s));
  }
  THEN("a value written unchanged is taken (an exported file imported again)") {
    CHECK(write_one("axis.y.seek_feedrate", reg("axis.y.seek_feedrate").default_raw, s));
  }
  THEN("a commutator slave's pull-off is its master's too") {
    homing::Settings c = s;
    c.axes[1].slave_mode = homing::SlaveMode::external_commutator;
    const auto refused = write_one("axis.y.pull_off", 1500, c);
    REQUIRE_FALSE(refused);
    CHECK(refused.error().reason == RefusalReason::slave_inherits);
  }
  THEN("an axis that is no slave yet takes them, and a request that makes it one may carry them") {
    homing::Settings free = with_x_y_homing();
    CHECK(write_one("axis.y.seek_feedrate", 5000, free));
    const Register& feed = reg("axis.y.seek_feedrate");
    const Register& slave_of = reg("axis.y.slave_of");
    // One request from the lower of the two addresses to the higher, every
    // register between written with its current value.
    const std::uint16_t first = std::min(slave_of.address, feed.address);
    const std::uint16_t last = std::max(slave_of.address, feed.address);
    std::vector<std::uint16_t> words(static_cast<std::size_t>(last - first + 1), 0);
    for (std::uint16_t a = first; a <= last; ++a) {
      const Register* r = find_register(Unit::module, Table::holding_register, a);
      if (r && r->address == a) {
        std::int64_t raw = setting_raw(free, *r);
        if (r == &slave_of) raw = 1;
        if (r == &feed) raw = 900;
        encode_words(*r, raw, WordOrder::high_first, std::span(words).subspan(a - first, r->words()));
      }
    }
    const auto ok = validate_write(Table::holding_register, first, words, WordOrder::high_first, free,
                                   default_host_registers());
    REQUIRE(ok);
    CHECK(ok->settings.axes[1].slave_of == 1);
    CHECK(ok->settings.axes[1].seek_feedrate_mm_per_min == 900);
  }
}

// The refusal above is only honest while the engine truly ignores these:
// every setting the write path calls inherited leaves what the slave moves
// with (motion_settings) unchanged, on both gantry topologies.
TEST_CASE("every setting a slave is refused changes nothing the slave moves with") {
  for (const homing::SlaveMode mode : {homing::SlaveMode::own_output, homing::SlaveMode::external_commutator}) {
    homing::Settings s = with_x_y_homing();
    s.axes[1].slave_of = 1;
    s.axes[1].slave_mode = mode;
    const homing::Settings before = homing::motion_settings(s);
    int inherited = 0;
    for (const Register& r : registers_of(Unit::module)) {
      if (!r.persisted || r.axis != 1) continue;
      const std::string field = r.name().substr(7);
      homing::AxisField f = homing::AxisField::none;
      for (const auto& info : homing::kAxisFieldInfo)
        if (info.name == field) f = info.value;
      if (!homing::inherited_from_master(f, mode)) continue;
      ++inherited;
      INFO(r.name());
      homing::Settings changed = s;
      const std::int64_t raw = setting_raw(s, r);
      set_setting_raw(changed, r, raw == r.max ? r.min : r.max);
      const homing::Settings after = homing::motion_settings(changed);
      for (const Register& other : registers_of(Unit::module))
        if (other.persisted && other.axis == 1) CHECK(setting_raw(after, other) == setting_raw(before, other));
      CHECK(homing::axis_kind(changed, 1) == homing::axis_kind(s, 1));
    }
    CHECK(inherited >= 20);
  }
}

TEST_CASE("a gantry that could not stop within its misalignment is refused at write time") {
  homing::Settings s = with_x_y_homing();
  s.axes[1].slave_of = 1;
  refused_naming(write_one("axis.x.jog_feedrate", 6000, s), "max_misalignment");
  refused_naming(write_one("axis.y.max_misalignment", 100, s), "max_misalignment");
}

TEST_CASE("a push the back-off cannot release is refused at write time") {
  homing::Settings s = with_x_y_homing();
  s.axes[0].mode = homing::HomingMode::pushing_release;
  s.axes[0].push_distance_mm = 1;
  refused_naming(write_one("axis.x.push_distance", 12000, s), "cannot release");
}

TEST_CASE("a shared limit without pull-off is refused at write time") {
  homing::Settings s = with_x_y_homing();
  s.axes[0].shared_limit = true;
  refused_naming(write_one("axis.x.pull_off", 0, s), "off its sensor");
}

TEST_CASE("a write that leaves an already broken setting as it was is taken") {
  // An old database may hold a combination the rules now refuse: writes that
  // do not touch it (or do not make it worse) still go through.
  homing::Settings s = with_x_y_homing();
  s.axes[2].mode = homing::HomingMode::switch_release;
  s.axes[2].latch_feedrate_mm_per_min = 5000;  // not slower than seek: broken
  CHECK(write_one("axis.x.pull_off", 2000, s));
  refused_naming(write_one("axis.y.latch_feedrate", 5000, s), "slower than seek_feedrate");
}

TEST_CASE("cmd.home_axes gives one command for the axes its bits name and holds nothing") {
  const auto s = default_settings();
  const auto ok = write_one("cmd.home_axes", 0b011, s);  // X and Y
  REQUIRE(ok);
  REQUIRE(ok->commands.size() == 1);
  CHECK(ok->commands[0] == CommandRequest{Command::home_axes, -1, true, 0b011});
  CHECK(ok->changes.empty());
  CHECK_FALSE(ok->changes_persisted());
  const homing::Status status{};
  CHECK(read_raw(reg("cmd.home_axes"), ModuleView{s, ok->host, status, StatusExtras{}}) == 0);
}

TEST_CASE("cmd.home_axes naming no axis, a disabled axis or a bit beyond C is exception 03") {
  const auto s = default_settings();  // A B C are disabled
  auto refused = write_one("cmd.home_axes", 0, s);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ExceptionCode::illegal_data_value);
  CHECK(refused.error().message.find("names no axis") != std::string::npos);
  refused = write_one("cmd.home_axes", 0b1001, s);  // X and A
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ExceptionCode::illegal_data_value);
  CHECK(refused.error().message.find("axis.a.mode is disabled") != std::string::npos);
  refused = write_one("cmd.home_axes", 64, s);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ExceptionCode::illegal_data_value);
}

TEST_CASE("a cmd.home_axes write the module cannot start now is 06 while busy and 04 while an alarm blocks homing") {
  const auto s = default_settings();
  const auto ok = write_one("cmd.home_axes", 0b100, s);
  REQUIRE(ok);
  homing::Status st{};
  st.interlocks = homing::interlock::not_homed;
  CHECK_FALSE(refusal_now(*ok, st));
  st.interlocks = homing::interlock::homing_active;
  auto r = refusal_now(*ok, st);
  REQUIRE(r);
  CHECK(r->code == ExceptionCode::server_device_busy);
  st.interlocks = homing::interlock::motion_active;
  CHECK(refusal_now(*ok, st)->code == ExceptionCode::server_device_busy);
  st.interlocks = homing::interlock::alarm_latched;
  r = refusal_now(*ok, st);
  REQUIRE(r);
  CHECK(r->code == ExceptionCode::server_device_failure);
  CHECK(r->message.find("an alarm is latched") != std::string::npos);
  st.interlocks = homing::interlock::estop | homing::interlock::alarm_latched;
  CHECK(refusal_now(*ok, st)->code == ExceptionCode::server_device_failure);
  // Coils keep their promise: refused through status.last_command_result, never an exception.
  const auto coil = write_one("cmd.home.x", 1, s);
  REQUIRE(coil);
  st.interlocks = homing::interlock::homing_active;
  CHECK_FALSE(refusal_now(*coil, st));
}
