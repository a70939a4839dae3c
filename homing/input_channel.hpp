#pragma once
// One home-sensor input as the engine reads it: the debounce filter, the
// edge and index pulse accepted this period, and the debounced state. An
// input belongs to an axis, but a commutator slave's switch is read on its
// master's input while the slave aligns, so phases reach it by channel.
#include "debounce.hpp"

namespace homing {

struct SensorEvent {
  bool edge = false;
  AcceptedEdge accepted{};  // to_level means "to active" (polarity applied)
  bool index = false;
  double index_mm = 0;      // motor position at the first index pulse of the period
};

struct InputChannel {
  Debouncer filter{};
  bool reset = false;          // a new source on this input: take its level as it is
  SensorEvent event{};         // this period's
  bool sensor_active = false;  // debounced, polarity applied
};

}  // namespace homing
