// What wakes an idle control loop on a cabinet (homing/gpiod/gpiod_io.hpp):
// every input line is requested with its edges' events, their descriptors
// are the backend's event_fds(), a period's read() drains them, and a
// debounced input about to count wakes the loop when it counts.
#include <catch2/catch.hpp>

#include <poll.h>

#include <cmath>
#include <string>
#include <vector>

#include "backend_fixture.hpp"

using homing::Outputs;
using homing::gpiod::GpiodIo;
using homing::gpiod::RunOptions;

namespace {

constexpr std::int64_t kMs = 1'000'000;

bool any_readable(std::span<const int> fds) {
  std::vector<pollfd> p;
  for (const int fd : fds) p.push_back(pollfd{fd, POLLIN, 0});
  return ::poll(p.data(), p.size(), 0) > 0;
}

const std::vector<std::string> kInputs = {"X.home", "X.index", "estop", "drive_fault", "start_button",
                                          "homing_permit"};

}  // namespace

TEST_CASE("every input line gives an event descriptor, and none is readable at rest") {
  fixture::Backend b;
  for (const std::string& role : kInputs) CHECK(b.chip->has_events(role));
  CHECK(b.io->event_fds().size() == kInputs.size());
  b.period(Outputs{}, kMs);
  CHECK_FALSE(any_readable(b.io->event_fds()));
  CHECK(std::isinf(b.io->quiet_for_s(Outputs{})));
}

TEST_CASE("an edge on any input makes a descriptor readable until the next period's read drains it") {
  for (const std::string& role : kInputs) {
    INFO(role);
    fixture::Backend b;
    b.period(Outputs{}, kMs);
    b.chip->play(role, b.now_ns + 200'000, !b.chip->value(role));
    CHECK(any_readable(b.io->event_fds()));
    b.period(Outputs{}, kMs);
    CHECK_FALSE(any_readable(b.io->event_fds()));
    CHECK_FALSE(b.chip->event_pending(role));
  }
}

TEST_CASE("an e-stop edge read in a period shows in that period's inputs") {
  fixture::Backend b;
  b.period(Outputs{}, kMs);
  CHECK_FALSE(b.period(Outputs{}, kMs).estop);
  b.chip->play("estop", b.now_ns + 100'000, true);  // pressed (the fake plays logical levels)
  CHECK(b.period(Outputs{}, kMs).estop);
}

TEST_CASE("a debounced input that changed tells the loop to wake when its debounce time ends") {
  fixture::Backend b;  // input_debounce_ms = 10
  b.period(Outputs{}, kMs);
  b.chip->play("start_button", b.now_ns + 100'000, true);  // pressed
  b.period(Outputs{}, kMs);
  CHECK(b.io->quiet_for_s(Outputs{}) == Approx(0.010));  // counts 10 ms after the end of the period that read it
  for (int i = 0; i < 9; ++i) CHECK_FALSE(b.period(Outputs{}, kMs).start_button);
  CHECK(b.period(Outputs{}, kMs).start_button);
  CHECK(std::isinf(b.io->quiet_for_s(Outputs{})));
}

TEST_CASE("an edge stamped after the period's end keeps the loop at the full rate: the next period takes it") {
  fixture::Backend b;
  b.period(Outputs{}, kMs);
  b.period(Outputs{}, kMs);
  b.chip->play("X.home", b.now_ns + 300'000, true);  // after the end of the period read below
  b.io->advance(Outputs{}, 0);
  b.io->read();
  CHECK(b.io->quiet_for_s(Outputs{}) == 0);
}

TEST_CASE("a line that gives no events is read as a level, with a warning that says so") {
  auto c = fixture::chip();
  c->chips["gpiochip0"].no_events.insert(22);  // homing_permit
  fake::Chip* chip = c.get();
  std::vector<std::string> warnings;
  RunOptions run;
  run.start_pulse_thread = false;
  run.warn = [&](const std::string& w) { warnings.push_back(w); };
  auto io = GpiodIo::open(fixture::config(), std::move(c), run);
  REQUIRE(io);
  CHECK_FALSE(chip->has_events("homing_permit"));
  CHECK(chip->has_events("estop"));
  CHECK((*io)->event_fds().size() == kInputs.size() - 1);
  REQUIRE(warnings.size() == 1);
  CHECK(warnings[0].find("homing_permit") != std::string::npos);
  CHECK(warnings[0].find("no edge events") != std::string::npos);
  chip->set_level_silently("homing_permit", true);
  (*io)->advance(Outputs{}, 0.001);
  (*io)->read();
  (*io)->advance(Outputs{}, 0.011);
  CHECK((*io)->read().homing_permit);  // still read, as a level
}
