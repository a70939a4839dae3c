#include <catch2/catch.hpp>

#include <map>
#include <set>
#include <string>

#include "registers/lookup.hpp"
#include "sparkplug/events.hpp"
#include "sparkplug/payload.hpp"

namespace {

using sparkplug::DataType;
using sparkplug::EdgeNode;
using sparkplug::Payload;

// A module whose registers read what the test put there (0 otherwise).
struct FakeModule {
  std::map<std::string, std::int64_t> raw;
  sparkplug::RawReader reader() const {
    return [this](const registers::Register& reg) {
      auto it = raw.find(reg.name());
      return it == raw.end() ? std::int64_t{0} : it->second;
    };
  }
};

const Payload::Metric* by_name(const Payload& p, std::string_view name) {
  for (const auto& m : p.metrics())
    if (m.name() == name) return &m;
  return nullptr;
}

std::uint64_t alias_of(const EdgeNode& node, std::string_view name) {
  for (const auto& def : node.metrics())
    if (def.name == name) return def.alias;
  FAIL("no metric " << name);
  return 0;
}

}  // namespace

TEST_CASE("every input register and discrete input of the module is a metric with a unique alias") {
  EdgeNode node;
  std::size_t expected = 0;
  for (const auto& reg : registers::registers_of(registers::Unit::module))
    if ((reg.table == registers::Table::input_register || reg.table == registers::Table::discrete_input) &&
        reg.key != registers::Key::status_heartbeat)
      ++expected;
  REQUIRE(node.metrics().size() == expected);
  std::set<std::uint64_t> aliases;
  std::set<std::string> names;
  for (const auto& def : node.metrics()) {
    CHECK(def.alias != 0);
    aliases.insert(def.alias);
    names.insert(def.name);
  }
  CHECK(aliases.size() == expected);
  CHECK(names.size() == expected);
  CHECK(names.contains("status/state"));
  CHECK(names.contains("axis/x/position"));
  CHECK(names.contains("axis/x/homed"));
  CHECK_FALSE(names.contains("axis/x/seek_feedrate"));  // settings are not published
}

TEST_CASE("datatypes follow the register type and scaled lengths go out as Double in mm") {
  CHECK(sparkplug::data_type(*registers::find_register("status.state")) == DataType::uint16);
  CHECK(sparkplug::data_type(*registers::find_register("axis.x.homed")) == DataType::boolean);
  CHECK(sparkplug::data_type(*registers::find_register("axis.x.position")) == DataType::dbl);
  FakeModule module;
  module.raw["axis.x.position"] = -12345;  // µm
  EdgeNode node;
  const Payload birth = node.birth(3, module.reader(), 1000);
  const auto* pos = by_name(birth, "axis/x/position");
  REQUIRE(pos != nullptr);
  CHECK(pos->datatype() == static_cast<std::uint32_t>(DataType::dbl));
  CHECK(pos->double_value() == Approx(-12.345));
}

TEST_CASE("birth carries seq 0, bdSeq, the rebirth control and every metric with name alias datatype and value") {
  FakeModule module;
  module.raw["status.state"] = 2;
  EdgeNode node;
  const Payload birth = node.birth(7, module.reader(), 1000);
  CHECK(birth.seq() == 0);
  CHECK(birth.timestamp() == 1000);
  const auto* bd = by_name(birth, "bdSeq");
  REQUIRE(bd != nullptr);
  CHECK(bd->datatype() == static_cast<std::uint32_t>(DataType::int64));
  CHECK(bd->long_value() == 7);
  const auto* rebirth = by_name(birth, "Node Control/Rebirth");
  REQUIRE(rebirth != nullptr);
  CHECK(rebirth->datatype() == static_cast<std::uint32_t>(DataType::boolean));
  CHECK_FALSE(rebirth->boolean_value());
  // bdSeq, Rebirth, the register metrics, then the event metrics (events_test.cpp).
  CHECK(static_cast<std::size_t>(birth.metrics_size()) == node.metrics().size() + 2 + sparkplug::kEventMetrics.size());
  for (const auto& def : node.metrics()) {
    const auto* m = by_name(birth, def.name);
    REQUIRE(m != nullptr);
    CHECK(m->alias() == def.alias);
    CHECK(m->datatype() == static_cast<std::uint32_t>(def.type));
    CHECK(m->value_case() != Payload::Metric::VALUE_NOT_SET);
  }
  CHECK(by_name(birth, "status/state")->int_value() == 2);
}

TEST_CASE("a signed 16 bit value travels as two's complement in int_value") {
  sparkplug::MetricDef def{"t", 1, DataType::int16, registers::find_register("status.state")};
  Payload::Metric m;
  sparkplug::set_value(m, def, -2);
  CHECK(m.int_value() == 0xFFFFFFFEu);
}

TEST_CASE("nothing is published before a birth nor when nothing changed") {
  FakeModule module;
  EdgeNode node;
  CHECK_FALSE(node.data(module.reader(), 1000).has_value());
  node.birth(0, module.reader(), 1000);
  CHECK_FALSE(node.data(module.reader(), 2000).has_value());
  CHECK_FALSE(node.data(module.reader(), 90000).has_value());
}

TEST_CASE("data carries only the changed metrics by alias without names") {
  FakeModule module;
  EdgeNode node;
  node.birth(0, module.reader(), 1000);
  module.raw["status.state"] = 3;
  module.raw["axis.y.homed"] = 1;
  const auto data = node.data(module.reader(), 1010);
  REQUIRE(data.has_value());
  REQUIRE(data->metrics_size() == 2);
  std::set<std::uint64_t> aliases;
  for (const auto& m : data->metrics()) {
    CHECK_FALSE(m.has_name());
    aliases.insert(m.alias());
  }
  CHECK(aliases == std::set<std::uint64_t>{alias_of(node, "status/state"), alias_of(node, "axis/y/homed")});
  CHECK_FALSE(node.data(module.reader(), 1020).has_value());  // published once, then quiet
}

TEST_CASE("a position is published only beyond its deadband and not faster than its rate limit") {
  sparkplug::ReportPolicy policy;
  policy.length_deadband = 0.01;  // mm
  policy.length_min_interval_ms = 100;
  FakeModule module;
  EdgeNode node(policy);
  node.birth(0, module.reader(), 1000);
  module.raw["axis.x.position"] = 9;  // 0.009 mm: inside the deadband
  CHECK_FALSE(node.data(module.reader(), 2000).has_value());
  module.raw["axis.x.position"] = 10;  // 0.010 mm: at the deadband
  const auto moved = node.data(module.reader(), 2000);
  REQUIRE(moved.has_value());
  REQUIRE(moved->metrics_size() == 1);
  CHECK(moved->metrics(0).double_value() == Approx(0.010));
  module.raw["axis.x.position"] = 500;
  CHECK_FALSE(node.data(module.reader(), 2050).has_value());  // 50 ms later: rate-limited
  const auto later = node.data(module.reader(), 2100);
  REQUIRE(later.has_value());
  CHECK(later->metrics(0).double_value() == Approx(0.5));
}

TEST_CASE("seq counts 1 to 255 after the birth then wraps to 0 and a rebirth restarts it") {
  FakeModule module;
  EdgeNode node;
  node.birth(0, module.reader(), 0);
  for (int n = 1; n <= 256; ++n) {
    module.raw["status.command_count"] = n;
    const auto data = node.data(module.reader(), n);
    REQUIRE(data.has_value());
    REQUIRE(data->seq() == static_cast<std::uint64_t>(n % 256));
  }
  CHECK(node.birth(1, module.reader(), 1000).seq() == 0);
  module.raw["status.command_count"] = 1;
  CHECK(node.data(module.reader(), 1001)->seq() == 1);
}

TEST_CASE("death carries the bdSeq of its birth and no seq") {
  const Payload death = EdgeNode::death(42);
  CHECK_FALSE(death.has_seq());
  REQUIRE(death.metrics_size() == 1);
  CHECK(death.metrics(0).name() == "bdSeq");
  CHECK(death.metrics(0).datatype() == static_cast<std::uint32_t>(DataType::int64));
  CHECK(death.metrics(0).long_value() == 42);
}

TEST_CASE("a payload survives the wire") {
  FakeModule module;
  module.raw["status.state"] = 1;
  EdgeNode node;
  const Payload birth = node.birth(5, module.reader(), 123);
  Payload back;
  REQUIRE(back.ParseFromString(birth.SerializeAsString()));
  CHECK(back.metrics_size() == birth.metrics_size());
  CHECK(by_name(back, "status/state")->int_value() == 1);
}

TEST_CASE("loop diagnostics are published at most every diagnostics interval and the heartbeat not at all") {
  sparkplug::ReportPolicy policy;
  policy.diagnostics_min_interval_ms = 10000;
  FakeModule module;
  EdgeNode node(policy);
  for (const auto& def : node.metrics()) CHECK(def.name != "status/heartbeat");
  node.birth(0, module.reader(), 1000);
  module.raw["status.heartbeat"] = 5;
  CHECK_FALSE(node.data(module.reader(), 1100).has_value());
  module.raw["diag.loop_late_p99_us"] = 17;
  CHECK_FALSE(node.data(module.reader(), 5000).has_value());
  const auto data = node.data(module.reader(), 11000);
  REQUIRE(data.has_value());
  REQUIRE(data->metrics_size() == 1);
  CHECK(data->metrics(0).alias() == alias_of(node, "diag/loop_late_p99_us"));
}
