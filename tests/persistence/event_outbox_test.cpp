// The MQTT event outbox: events kept durably in order until delivered,
// bounded with the oldest dropped and counted, and the settings audit cursor
// moved with the event it made, and the Sparkplug bdSeq of each session.
#include <catch2/catch.hpp>

#include "persistence/event_outbox.hpp"
#include "tests/support/temp_dir.hpp"

using persistence::Event;
using persistence::EventKind;
using persistence::EventOutbox;

namespace {

Event cycle(std::int64_t t) {
  Event e;
  e.time_ms = t;
  e.kind = EventKind::cycle_ended;
  e.duration_ms = 1234;
  e.axes = 7;
  e.text = "homing done in 1234 ms";
  return e;
}

}  // namespace

TEST_CASE("events survive closing and reopening the outbox, oldest first, until delivered") {
  test_support::TempDir dir;
  const auto path = dir.file("o.db");
  {
    auto box = EventOutbox::open(path, 100);
    REQUIRE(box);
    for (int i = 0; i < 5; ++i) REQUIRE(box->push(cycle(1000 + i)));
  }
  auto box = EventOutbox::open(path, 100);
  REQUIRE(box);
  auto all = box->oldest(10);
  REQUIRE(all);
  REQUIRE(all->size() == 5);
  CHECK((*all)[0].time_ms == 1000);
  CHECK((*all)[4].time_ms == 1004);
  CHECK((*all)[2].text == "homing done in 1234 ms");
  CHECK((*all)[2].duration_ms == 1234);
  CHECK((*all)[2].axes == 7);
  REQUIRE(box->remove_through((*all)[2].id));
  auto rest = box->oldest(10);
  REQUIRE(rest->size() == 2);
  CHECK((*rest)[0].time_ms == 1003);
  auto after = box->oldest(10, (*rest)[0].id);
  REQUIRE(after->size() == 1);
  CHECK((*after)[0].time_ms == 1004);
}

TEST_CASE("past its bound the outbox drops the oldest events and counts them, ids never reused") {
  test_support::TempDir dir;
  auto box = EventOutbox::open(dir.file("o.db"), 3);
  REQUIRE(box);
  std::int64_t last = 0;
  for (int i = 0; i < 5; ++i) last = *box->push(cycle(i));
  CHECK(box->size() == 3);
  CHECK(box->dropped() == 2);
  auto kept = box->oldest(10);
  REQUIRE(kept->size() == 3);
  CHECK((*kept)[0].time_ms == 2);
  CHECK((*kept)[2].id == last);
  REQUIRE(box->remove_through(last));
  CHECK(*box->push(cycle(9)) == last + 1);
}

TEST_CASE("a settings change moves the audit cursor in the same commit as its event") {
  test_support::TempDir dir;
  auto box = EventOutbox::open(dir.file("o.db"), 10);
  REQUIRE(box);
  CHECK_FALSE(box->audit_cursor());
  Event e;
  e.kind = EventKind::setting_changed;
  e.name = "axis.x.pull_off";
  REQUIRE(box->push(e, 17));
  CHECK(box->audit_cursor() == 17);
  REQUIRE(box->push(cycle(1)));
  CHECK(box->audit_cursor() == 17);  // other events leave it
}

TEST_CASE("an outbox that cannot be created says which file and why") {
  const auto box = EventOutbox::open("/nonexistent-dir/o.db", 10);
  REQUIRE_FALSE(box);
  CHECK(box.error().message.find("/nonexistent-dir/o.db") != std::string::npos);
}

TEST_CASE("the last Sparkplug bdSeq kept is there after a restart, none in a new outbox") {
  test_support::TempDir dir;
  const auto path = dir.file("o.db");
  {
    auto box = EventOutbox::open(path, 100);
    REQUIRE(box);
    auto none = box->last_bd_seq();
    REQUIRE(none);
    CHECK_FALSE(none->has_value());
    REQUIRE(box->keep_bd_seq(0));
    REQUIRE(box->keep_bd_seq(255));
  }
  auto box = EventOutbox::open(path, 100);  // a restart (or a power cut)
  REQUIRE(box);
  auto last = box->last_bd_seq();
  REQUIRE(last);
  CHECK(*last == std::optional<std::uint64_t>{255});
}
