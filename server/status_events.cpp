#include "status_events.hpp"

namespace server {

void StatusEvents::add(StatusEvent e) {
  e.seq = ++written_;
  ring_[e.seq % kRing] = e;
}

const StatusEvent* StatusEvents::find(std::uint64_t seq) const {
  if (seq == 0 || seq > written_ || written_ - seq >= kRing) return nullptr;
  return &ring_[seq % kRing];
}

void StatusEvents::observe(const homing::Status& now, std::int64_t now_ms) {
  if (!started_) {
    // What is latched at start is news too (settings lost, an e-stop pressed).
    started_ = true;
    last_ = homing::Status{};
  }
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const homing::Alarm& alarm = now.axes[a].alarm;
    if (alarm && alarm.code != last_.axes[a].alarm.code)
      add({.kind = StatusEventKind::alarm_raised, .axis = static_cast<std::int8_t>(a), .code = alarm.code, .alarm = alarm,
           .time_ms = now_ms});
  }
  if (now.global_alarm != homing::AlarmCode::none && now.global_alarm != last_.global_alarm)
    add({.kind = StatusEventKind::alarm_raised, .code = now.global_alarm, .time_ms = now_ms});
  if (last_.alarm && !now.alarm) add({.kind = StatusEventKind::alarms_reset, .time_ms = now_ms});
  // A reference check is no homing cycle (docs/homing-methods.md): its
  // alarms are news, the check itself is not reported as a cycle.
  const bool cycle_now = now.homing && !now.reference_check;
  const bool cycle_before = last_.homing && !last_.reference_check;
  if (cycle_now) {
    if (!cycle_before) {
      cycle_start_ms_ = now_ms;
      cycle_axes_ = 0;
    }
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (now.axes[a].busy) cycle_axes_ |= homing::axis_bit(a);
    if (!cycle_before) add({.kind = StatusEventKind::cycle_started, .axes = cycle_axes_, .time_ms = now_ms});
  }
  if (!cycle_now && cycle_before) {
    StatusEvent e{.kind = StatusEventKind::cycle_ended, .axes = cycle_axes_, .time_ms = now_ms,
                  .duration_ms = now_ms - cycle_start_ms_};
    if (const int a = homing::reported_alarm_axis(now); a >= 0) {
      e.code = now.axes[static_cast<std::size_t>(a)].alarm.code;
      e.alarm = now.axes[static_cast<std::size_t>(a)].alarm;
      e.axis = static_cast<std::int8_t>(a);
    }
    if (e.code == homing::AlarmCode::none) e.code = now.global_alarm;
    add(e);
  }
  last_ = now;
}

}  // namespace server
