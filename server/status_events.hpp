#pragma once
// What changed in the engine's status from one control period to the next
// that the plant must hear of (an alarm raised, alarms reset, a homing cycle
// started or ended; a reference check is no homing cycle), recorded by the control loop every period into a ring
// that the snapshot carries. Readers that sample the snapshot now and then
// (the monitor every 10 ms) still see an alarm raised and reset between two
// of their looks.
#include <array>
#include <cstdint>

#include "homing/status.hpp"

namespace server {

enum class StatusEventKind : std::uint8_t { alarm_raised, alarms_reset, cycle_started, cycle_ended };

struct StatusEvent {
  std::uint64_t seq = 0;  // 1, 2, ...: a reader takes those after the last it took
  StatusEventKind kind = StatusEventKind::alarm_raised;
  std::int8_t axis = -1;  // -1: the machine (a global alarm, a cycle)
  homing::AlarmCode code = homing::AlarmCode::none;  // the alarm; a cycle's end: the first alarm of its axes, none = homed
  homing::Alarm alarm{};                             // the axis alarm whole (its text needs it)
  homing::AxisMask axes = 0;                         // a cycle: its axes
  std::int64_t time_ms = 0;                          // Unix ms
  std::int64_t duration_ms = 0;                      // cycle_ended
};

class StatusEvents {
 public:
  static constexpr std::size_t kRing = 64;
  // One period's status after the last; now_ms is the wall clock.
  void observe(const homing::Status& now, std::int64_t now_ms);
  std::uint64_t written() const { return written_; }
  // The event with this seq, if the ring still holds it.
  const StatusEvent* find(std::uint64_t seq) const;

 private:
  void add(StatusEvent e);
  std::array<StatusEvent, kRing> ring_{};
  std::uint64_t written_ = 0;
  homing::Status last_{};
  bool started_ = false;
  std::int64_t cycle_start_ms_ = 0;
  homing::AxisMask cycle_axes_ = 0;
};

}  // namespace server
