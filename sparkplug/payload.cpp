#include "sparkplug/payload.hpp"

#include <cmath>

#include "registers/codec.hpp"
#include "sparkplug/events.hpp"

namespace sparkplug {

EdgeNode::EdgeNode(ReportPolicy policy)
    : policy_(policy),
      metrics_(node_metrics()),
      sent_raw_(metrics_.size(), 0),
      sent_at_ms_(metrics_.size(), 0) {}

void set_value(Payload::Metric& metric, const MetricDef& def, std::int64_t raw) {
  metric.set_datatype(static_cast<std::uint32_t>(def.type));
  switch (def.type) {
    case DataType::dbl: metric.set_double_value(registers::to_engineering(*def.reg, raw)); break;
    case DataType::boolean: metric.set_boolean_value(raw != 0); break;
    case DataType::int64: metric.set_long_value(static_cast<std::uint64_t>(raw)); break;
    // Int8/16/32 and UInt8/16/32 travel in int_value; signed ones as two's complement.
    case DataType::int16:
    case DataType::int32:
    case DataType::uint16:
    case DataType::uint32:
      metric.set_int_value(static_cast<std::uint32_t>(static_cast<std::int64_t>(raw)));
      break;
  }
}

std::uint64_t EdgeNode::next_seq() {
  seq_ = static_cast<std::uint8_t>(seq_ + 1);  // 255 + 1 wraps to 0 as the specification wants
  return seq_;
}

Payload EdgeNode::birth(std::uint64_t bd_seq, const RawReader& read, std::uint64_t now_ms, std::int64_t events_dropped) {
  Payload p;
  p.set_timestamp(now_ms);
  seq_ = 0;
  p.set_seq(seq_);
  auto* bd = p.add_metrics();
  bd->set_name(std::string(kBdSeqName));
  bd->set_timestamp(now_ms);
  bd->set_datatype(static_cast<std::uint32_t>(DataType::int64));
  bd->set_long_value(bd_seq);
  auto* rebirth = p.add_metrics();
  rebirth->set_name(std::string(kRebirthName));
  rebirth->set_timestamp(now_ms);
  rebirth->set_datatype(static_cast<std::uint32_t>(DataType::boolean));
  rebirth->set_boolean_value(false);
  for (std::size_t i = 0; i < metrics_.size(); ++i) {
    const auto& def = metrics_[i];
    const std::int64_t raw = read(*def.reg);
    auto* m = p.add_metrics();
    m->set_name(def.name);
    m->set_alias(def.alias);
    m->set_timestamp(now_ms);
    set_value(*m, def, raw);
    remember(i, raw, now_ms);
  }
  add_event_metrics(p, first_event_alias(), now_ms, events_dropped);
  born_ = true;
  return p;
}

std::optional<Payload> EdgeNode::event(const persistence::Event& e, bool historical, std::int64_t events_dropped,
                                       std::uint64_t now_ms) {
  if (!born_) return std::nullopt;
  Payload p;
  add_event(p, e, historical, first_event_alias(), events_dropped);
  p.set_timestamp(now_ms);
  p.set_seq(next_seq());
  return p;
}

bool EdgeNode::changed(std::size_t i, std::int64_t raw, std::uint64_t now_ms) const {
  if (raw == sent_raw_[i]) return false;
  const auto& reg = *metrics_[i].reg;
  if (is_diagnostic(reg)) return now_ms - sent_at_ms_[i] >= policy_.diagnostics_min_interval_ms;
  if (reg.quantity != registers::Quantity::length_um) return true;
  if (now_ms - sent_at_ms_[i] < policy_.length_min_interval_ms) return false;
  const double moved = std::abs(registers::to_engineering(reg, raw) - registers::to_engineering(reg, sent_raw_[i]));
  return moved >= policy_.length_deadband;
}

void EdgeNode::remember(std::size_t i, std::int64_t raw, std::uint64_t now_ms) {
  sent_raw_[i] = raw;
  sent_at_ms_[i] = now_ms;
}

std::optional<Payload> EdgeNode::data(const RawReader& read, std::uint64_t now_ms) {
  if (!born_) return std::nullopt;
  Payload p;
  for (std::size_t i = 0; i < metrics_.size(); ++i) {
    const std::int64_t raw = read(*metrics_[i].reg);
    if (!changed(i, raw, now_ms)) continue;
    auto* m = p.add_metrics();
    m->set_alias(metrics_[i].alias);
    m->set_timestamp(now_ms);
    set_value(*m, metrics_[i], raw);
    remember(i, raw, now_ms);
  }
  if (p.metrics_size() == 0) return std::nullopt;
  p.set_timestamp(now_ms);
  p.set_seq(next_seq());
  return p;
}

Payload EdgeNode::death(std::uint64_t bd_seq) {
  Payload p;
  auto* bd = p.add_metrics();
  bd->set_name(std::string(kBdSeqName));
  bd->set_datatype(static_cast<std::uint32_t>(DataType::int64));
  bd->set_long_value(bd_seq);
  return p;
}

}  // namespace sparkplug
