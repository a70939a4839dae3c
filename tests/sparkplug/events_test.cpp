// Plant events on Sparkplug B: declared in every birth after the register
// metrics, one NDATA per event stamped with the time it happened.
#include <catch2/catch.hpp>

#include <map>

#include "sparkplug/events.hpp"
#include "sparkplug/payload.hpp"

namespace {

std::int64_t zero(const registers::Register&) { return 0; }

}  // namespace

TEST_CASE("every birth declares the event metrics with names, aliases after the registers' and datatypes") {
  sparkplug::EdgeNode node;
  const auto birth = node.birth(3, zero, 1000, 7);
  std::map<std::string, const sparkplug::Payload::Metric*> by_name;
  for (const auto& m : birth.metrics()) by_name[m.name()] = &m;
  for (std::size_t i = 0; i < sparkplug::kEventMetrics.size(); ++i) {
    const auto& def = sparkplug::kEventMetrics[i];
    INFO(def.name);
    REQUIRE(by_name.count(std::string(def.name)));
    CHECK(by_name[std::string(def.name)]->alias() == node.first_event_alias() + i);
    CHECK(by_name[std::string(def.name)]->datatype() == static_cast<std::uint32_t>(def.type));
  }
  CHECK(by_name["event/dropped"]->long_value() == 7);
  CHECK(node.first_event_alias() == node.metrics().size() + 1);
}

TEST_CASE("an event is one NDATA stamped with its own time, historical when sent late, seq continuing") {
  sparkplug::EdgeNode node;
  persistence::Event e;
  CHECK_FALSE(node.event(e, false, 0, 5000));  // nothing before a birth
  node.birth(0, zero, 1000);
  e.id = 42;
  e.time_ms = 900;
  e.kind = persistence::EventKind::setting_changed;
  e.name = "axis.x.seek_feedrate";
  e.old_value = 1000;
  e.new_value = 1200;
  e.text = "axis.x.seek_feedrate 1000 -> 1200 by tcp 10.0.0.5:5020";
  const auto p = node.event(e, true, 2, 5000);
  REQUIRE(p);
  CHECK(p->seq() == 1);
  CHECK(p->timestamp() == 5000);
  std::map<std::uint64_t, const sparkplug::Payload::Metric*> by_alias;
  for (const auto& m : p->metrics()) {
    CHECK(m.timestamp() == 900);
    CHECK(m.is_historical());
    CHECK_FALSE(m.has_name());
    by_alias[m.alias()] = &m;
  }
  const auto a = node.first_event_alias();
  CHECK(by_alias.at(a + 0)->long_value() == 42);
  CHECK(by_alias.at(a + 1)->string_value() == "setting_changed");
  CHECK(by_alias.at(a + 6)->string_value() == "axis.x.seek_feedrate");
  CHECK(by_alias.at(a + 7)->long_value() == 1000);
  CHECK(by_alias.at(a + 8)->long_value() == 1200);
  CHECK(by_alias.at(a + 9)->string_value() == e.text);
  CHECK(by_alias.at(a + 10)->long_value() == 2);
  CHECK_FALSE(by_alias.count(a + 4));  // no duration: not a cycle
}
