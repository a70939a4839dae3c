#pragma once
// Sparkplug B payloads of the edge node, built from the register table's
// metrics (node_metrics.hpp): NBIRTH with bdSeq and every metric's name,
// alias, datatype and value; NDATA by exception with aliases only; NDEATH with
// the bdSeq of its birth. Pure: values and the time come in, payloads go out;
// the MQTT client that sends them lives elsewhere.
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "persistence/event_outbox.hpp"
#include "sparkplug/node_metrics.hpp"
#include "sparkplug_b.pb.h"

namespace sparkplug {

using Payload = org::eclipse::tahu::protobuf::Payload;
// A metric's current raw register value (registers::read_raw over a snapshot).
using RawReader = std::function<std::int64_t(const registers::Register&)>;

// What counts as a change worth publishing.
struct ReportPolicy {
  // Lengths (positions, corrections, distances) are published when they moved
  // by at least this much from the value last published, in mm (deg on rotary axes)...
  double length_deadband = 0.01;
  // ...and not more often than this per metric: a moving axis is sampled, not streamed.
  std::uint64_t length_min_interval_ms = 100;
  // Diagnostics (is_diagnostic) change every period: any change, at most this often.
  std::uint64_t diagnostics_min_interval_ms = 10000;
};

class EdgeNode {
 public:
  explicit EdgeNode(ReportPolicy policy = {});

  const std::vector<MetricDef>& metrics() const { return metrics_; }

  // NBIRTH: seq restarts at 0; bdSeq first, then every metric with name,
  // alias, datatype and current value. Also the answer to a rebirth request.
  // The event metrics (events.hpp) follow the register metrics, with the
  // outbox's count of dropped events.
  Payload birth(std::uint64_t bd_seq, const RawReader& read, std::uint64_t now_ms, std::int64_t events_dropped = 0);
  // NDATA with the metrics that changed since they were last published
  // (aliases only, no names); nothing before a birth or when nothing changed.
  std::optional<Payload> data(const RawReader& read, std::uint64_t now_ms);
  // NDATA of one plant event, at the time it happened; historical when it is
  // sent late (it happened before this session's birth); the payload's own
  // timestamp is when it is sent. Only after a birth.
  std::optional<Payload> event(const persistence::Event& event, bool historical, std::int64_t events_dropped,
                               std::uint64_t now_ms);
  std::uint64_t first_event_alias() const { return metrics_.size() + 1; }
  // NDEATH (the MQTT Will): bdSeq only, no seq, as the specification says.
  static Payload death(std::uint64_t bd_seq);

 private:
  std::uint64_t next_seq();
  bool changed(std::size_t i, std::int64_t raw, std::uint64_t now_ms) const;
  void remember(std::size_t i, std::int64_t raw, std::uint64_t now_ms);

  ReportPolicy policy_;
  std::vector<MetricDef> metrics_;
  std::vector<std::int64_t> sent_raw_;
  std::vector<std::uint64_t> sent_at_ms_;
  bool born_ = false;
  std::uint8_t seq_ = 0;  // of the last message sent; wraps 255 -> 0
};

// The value of a metric on the wire in the field its datatype names.
void set_value(Payload::Metric& metric, const MetricDef& def, std::int64_t raw);

}  // namespace sparkplug
