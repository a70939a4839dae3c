// Every start-up error names the chip and the line and says what to do; the
// lines taken before the failure are given back.
#include <catch2/catch.hpp>

#include <cerrno>

#include "backend_fixture.hpp"
#include "homing/gpiod/gpiod_lines.hpp"

using namespace homing::gpiod;

namespace {
std::string open_error(std::unique_ptr<fake::Chip> chip, const BackendConfig& cfg = fixture::config()) {
  auto io = GpiodIo::open(cfg, std::move(chip), RunOptions{.start_pulse_thread = false});
  return io ? std::string("(opened)") : io.error();
}
}  // namespace

TEST_CASE("start-up: a missing chip") {
  auto chip = fixture::chip();
  chip->chips.clear();
  CHECK(open_error(std::move(chip)) ==
        "X.step (gpiochip0 line 23): cannot open GPIO chip 'gpiochip0': no such GPIO chip (see 'gpiodetect' for "
        "the chips this board has)");
}

TEST_CASE("start-up: a line offset beyond the chip") {
  auto chip = fixture::chip();
  chip->chips["gpiochip0"].lines = 25;
  CHECK(open_error(std::move(chip)) == "X.enable (gpiochip0 line 25): chip 'gpiochip0' has lines 0..24, there is no line 25");
}

TEST_CASE("start-up: a line name that no chip has") {
  auto chip = fixture::chip();
  chip->chips["gpiochip0"].names.clear();
  CHECK_THAT(open_error(std::move(chip)),
             Catch::StartsWith("start_button (gpiochip0 line \"START\"): chip 'gpiochip0' has no line named \"START\""));
}

TEST_CASE("start-up: a line in use by another program") {
  auto chip = fixture::chip();
  chip->chips["gpiochip0"].busy[4] = "spi0 CS1";
  CHECK_THAT(open_error(std::move(chip)),
             Catch::StartsWith("X.home (gpiochip0 line 4): the line is in use by 'spi0 CS1'"));
}

TEST_CASE("start-up: no permission on the chip") {
  auto chip = fixture::chip();
  chip->chips["gpiochip0"].open_errno = EACCES;
  CHECK_THAT(open_error(std::move(chip)),
             Catch::Contains("X.step (gpiochip0 line 23): cannot open GPIO chip 'gpiochip0': permission denied: run "
                             "homingd as a user in the 'gpio' group"));
}

TEST_CASE("start-up: a line name searched on every chip") {
  auto cfg = fixture::config();
  cfg.start_button->chip.clear();
  auto chip = fixture::chip();
  chip->chips["gpiochip0"].names.clear();
  CHECK(open_error(std::move(chip), cfg) ==
        "start_button (line \"START\"): no GPIO line is named \"START\" on any chip (see 'gpioinfo')");
}

TEST_CASE("start-up through libgpiod itself: a chip that does not exist on this machine") {
  GpiodLines lines;
  auto r = lines.request_output(LineSpec{"X.step", "gpiochip-does-not-exist", 23u}, false);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error(), Catch::StartsWith("X.step (gpiochip-does-not-exist line 23): cannot open GPIO chip "
                                          "'gpiochip-does-not-exist': "));
}
