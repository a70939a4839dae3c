#include "sparkplug/events.hpp"

#include <string>

#include "homing/axes.hpp"

namespace sparkplug {
namespace {

using Metric = org::eclipse::tahu::protobuf::Payload::Metric;

enum Field : std::size_t { id, kind, axis, code, duration_ms, axes, setting, old_value, new_value, text, dropped };

Metric& add(org::eclipse::tahu::protobuf::Payload& p, Field f, std::uint64_t first_alias, std::uint64_t time_ms,
            bool historical) {
  Metric& m = *p.add_metrics();
  m.set_alias(first_alias + f);
  m.set_timestamp(time_ms);
  m.set_datatype(static_cast<std::uint32_t>(kEventMetrics[f].type));
  if (historical) m.set_is_historical(true);
  return m;
}

std::string axis_letter(std::int32_t axis) {
  if (axis < 0 || axis >= static_cast<std::int32_t>(homing::kAxisCount)) return {};
  return std::string(1, homing::kAxisUpper[static_cast<std::size_t>(axis)]);
}

}  // namespace

void add_event_metrics(org::eclipse::tahu::protobuf::Payload& birth, std::uint64_t first_alias, std::uint64_t now_ms,
                       std::int64_t dropped_so_far) {
  for (std::size_t f = 0; f < kEventMetrics.size(); ++f) {
    Metric& m = *birth.add_metrics();
    m.set_name(std::string(kEventMetrics[f].name));
    m.set_alias(first_alias + f);
    m.set_timestamp(now_ms);
    m.set_datatype(static_cast<std::uint32_t>(kEventMetrics[f].type));
    switch (kEventMetrics[f].type) {
      case DataType::string: m.set_string_value(""); break;
      case DataType::int64: m.set_long_value(f == dropped ? static_cast<std::uint64_t>(dropped_so_far) : 0); break;
      default: m.set_int_value(0); break;
    }
  }
}

void add_event(org::eclipse::tahu::protobuf::Payload& p, const persistence::Event& e, bool historical,
               std::uint64_t first_alias, std::int64_t dropped_so_far) {
  const auto t = static_cast<std::uint64_t>(e.time_ms);
  add(p, id, first_alias, t, historical).set_long_value(static_cast<std::uint64_t>(e.id));
  add(p, kind, first_alias, t, historical).set_string_value(std::string(persistence::event_kind_name(e.kind)));
  add(p, axis, first_alias, t, historical).set_string_value(axis_letter(e.axis));
  add(p, code, first_alias, t, historical).set_int_value(static_cast<std::uint32_t>(e.code));
  switch (e.kind) {
    case persistence::EventKind::cycle_started:
    case persistence::EventKind::cycle_ended:
      add(p, duration_ms, first_alias, t, historical).set_long_value(static_cast<std::uint64_t>(e.duration_ms));
      add(p, axes, first_alias, t, historical).set_int_value(static_cast<std::uint32_t>(e.axes));
      break;
    case persistence::EventKind::command:
    case persistence::EventKind::setting_changed:
      add(p, setting, first_alias, t, historical).set_string_value(e.name);
      add(p, old_value, first_alias, t, historical).set_long_value(static_cast<std::uint64_t>(e.old_value));
      add(p, new_value, first_alias, t, historical).set_long_value(static_cast<std::uint64_t>(e.new_value));
      break;
    case persistence::EventKind::alarm_raised:
    case persistence::EventKind::alarms_reset: break;
  }
  add(p, text, first_alias, t, historical).set_string_value(e.text);
  add(p, dropped, first_alias, t, historical).set_long_value(static_cast<std::uint64_t>(dropped_so_far));
}

}  // namespace sparkplug
