#pragma once
// Plant events on Sparkplug B: the metrics under event/ that every NBIRTH
// declares after the register metrics, and one NDATA per event, stamped with
// the time it happened and marked historical when it is sent late (kept in
// the outbox while the broker was away). Pure: events in, payloads out.
#include <array>
#include <cstdint>
#include <string_view>

#include "persistence/event_outbox.hpp"
#include "sparkplug/node_metrics.hpp"
#include "sparkplug_b.pb.h"

namespace sparkplug {

struct EventMetric {
  std::string_view name;
  DataType type;
};

// In alias order, right after the register metrics.
inline constexpr std::array kEventMetrics = {
    EventMetric{"event/id", DataType::int64},          // increasing; a gap = events dropped by the bound
    EventMetric{"event/kind", DataType::string},       // cycle_started, cycle_ended, alarm_raised, alarms_reset, setting_changed, command
    EventMetric{"event/axis", DataType::string},       // X..C, empty for the machine
    EventMetric{"event/code", DataType::uint16},       // the alarm code; a cycle's result (0 = homed); a command's refusal reason (0 = accepted)
    EventMetric{"event/duration_ms", DataType::int64}, // cycle_ended
    EventMetric{"event/axes", DataType::uint16},       // a cycle's axes, bit 0 = X
    EventMetric{"event/setting", DataType::string},    // setting_changed, command: the register name
    EventMetric{"event/old_value", DataType::int64},   // setting_changed: raw register values
    EventMetric{"event/new_value", DataType::int64},
    EventMetric{"event/text", DataType::string},       // what a technician reads
    EventMetric{"event/dropped", DataType::int64},     // events the outbox's bound has dropped so far
};

// The event metrics of a birth, with empty values, aliases from first_alias on.
void add_event_metrics(org::eclipse::tahu::protobuf::Payload& birth, std::uint64_t first_alias, std::uint64_t now_ms,
                       std::int64_t dropped);
// The metrics of one event (aliases only), each stamped with the event's time.
void add_event(org::eclipse::tahu::protobuf::Payload& data, const persistence::Event& event, bool historical,
               std::uint64_t first_alias, std::int64_t dropped);

}  // namespace sparkplug
