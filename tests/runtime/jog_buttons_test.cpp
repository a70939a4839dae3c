// The jog coils as buttons several clients may hold (server/jog_buttons.hpp).
#include <catch2/catch.hpp>

#include "server/jog_buttons.hpp"

using server::JogButtons;

namespace {
constexpr std::uint64_t plc = 1, panel = 2;
constexpr std::int8_t plus = 1, minus = -1;
}  // namespace

TEST_CASE("a jog button starts on a press and any holder's release stops it for all") {
  JogButtons b;
  CHECK(b.write(0, plus, true, plc) == plus);
  CHECK(b.held(0, plus));
  CHECK(b.write(0, plus, true, panel) == std::nullopt);  // held already: joins
  CHECK(b.write(0, plus, false, panel) == std::int8_t{0});
  CHECK_FALSE(b.held(0, plus));
  // Released for all: the first holder's 0 changes nothing more.
  CHECK(b.write(0, plus, false, plc) == std::nullopt);
}

TEST_CASE("a jog button's 0 from a client that never held it changes nothing") {
  JogButtons b;
  CHECK(b.write(2, minus, true, plc) == minus);
  CHECK(b.write(2, minus, false, panel) == std::nullopt);
  CHECK(b.held(2, minus));
}

TEST_CASE("both jog directions held is no jog and releasing one starts nothing") {
  JogButtons b;
  CHECK(b.write(1, plus, true, plc) == plus);
  CHECK(b.write(1, minus, true, panel) == std::int8_t{0});
  CHECK(b.held(1, plus));
  CHECK(b.held(1, minus));
  CHECK(b.write(1, minus, false, panel) == std::int8_t{0});
  CHECK(b.write(1, plus, true, plc) == std::nullopt);  // still held, no new press
  CHECK(b.write(1, plus, false, plc) == std::int8_t{0});
  CHECK(b.write(1, plus, true, plc) == plus);  // a press
}

TEST_CASE("a disconnect releases every jog button its client holds on every axis and no other") {
  JogButtons b;
  CHECK(b.write(0, plus, true, plc) == plus);
  CHECK(b.write(3, minus, true, plc) == minus);
  CHECK(b.write(5, plus, true, panel) == plus);
  CHECK(b.write(3, plus, true, panel) == std::int8_t{0});
  CHECK(b.disconnected(plc) == static_cast<homing::AxisMask>(homing::axis_bit(0) | homing::axis_bit(3)));
  CHECK_FALSE(b.held(0, plus));
  CHECK_FALSE(b.held(3, minus));
  CHECK(b.held(3, plus));  // the panel's own button stays held
  CHECK(b.held(5, plus));
  CHECK(b.disconnected(plc) == 0);
}
