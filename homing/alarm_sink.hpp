#pragma once
// The one way a phase raises an alarm: handed to the phases by the engine,
// whose alarm path (alarm_path.cpp) latches it and stops every axis.
#include "alarms.hpp"
#include "axes.hpp"

namespace homing {

class AlarmSink {
 public:
  virtual void raise(AxisMask axes, Alarm alarm) = 0;

 protected:
  ~AlarmSink() = default;
};

}  // namespace homing
