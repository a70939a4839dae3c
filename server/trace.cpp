#include "trace.hpp"

#include <algorithm>
#include <cmath>

namespace server {

void TraceRecorder::begin(double period_s) {
  for (AxisTrace& t : traces_) {
    t.count = 0;
    t.reference_time_s.reset();
    t.alarm = homing::Alarm{};
  }
  involved_.fill(false);
  period_s_ = period_s;
  stride_ = 1;
  tick_ = 0;
  start_s_ = -1;
  latest_kept_ = true;
  active_ = true;
}

void TraceRecorder::record(double time_s, const homing::Status& status,
                           const std::array<double, homing::kAxisCount>& motor_mm) {
  if (!active_) return;
  if (start_s_ < 0) start_s_ = time_s;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const homing::AxisStatus& s = status.axes[a];
    if (s.busy) involved_[a] = true;
    AxisTrace& t = traces_[a];
    // The reference edge is found when the axis enters pull-off.
    if (involved_[a] && !t.reference_time_s && s.phase == homing::Phase::pull_off)
      t.reference_time_s = time_s - start_s_;
  }
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    const homing::AxisStatus& s = status.axes[a];
    latest_[a] = TraceSample{time_s - start_s_, s.phase, motor_mm[a], s.velocity_mm_per_s, s.sensor};
  }
  latest_kept_ = tick_++ % stride_ == 0;
  if (latest_kept_) keep_latest();
}

void TraceRecorder::keep_latest() {
  if (traces_[0].count == kTraceCapacity) {
    // Full: keep every other sample and halve the rate from now on.
    for (AxisTrace& t : traces_) {
      for (std::size_t i = 0; i < kTraceCapacity / 2; ++i) t.samples[i] = t.samples[2 * i];
      t.count = kTraceCapacity / 2;
    }
    stride_ *= 2;
  }
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    AxisTrace& t = traces_[a];
    t.samples[t.count++] = latest_[a];
  }
  latest_kept_ = true;
}

void TraceRecorder::finish(double time_s, const homing::Status& status,
                           const std::array<double, homing::kAxisCount>& motor_mm) {
  if (!active_) return;
  if (!latest_kept_) keep_latest();
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    AxisTrace& t = traces_[a];
    const homing::AxisStatus& s = status.axes[a];
    t.interval_s = period_s_ * static_cast<double>(stride_);
    t.offset_mm = s.position_mm - motor_mm[a];
    t.reference_mm = s.trigger_position_mm + s.home_correction_mm;
    t.alarm = s.alarm;
    t.duration_s = start_s_ < 0 ? 0 : time_s - start_s_;
    if (!involved_[a]) t.count = 0;
  }
  active_ = false;
}

namespace {

void put32(std::vector<std::uint16_t>& out, std::size_t at, std::int64_t v) {
  const auto u = static_cast<std::uint32_t>(v);
  out[at] = static_cast<std::uint16_t>(u >> 16);
  out[at + 1] = static_cast<std::uint16_t>(u & 0xFFFF);
}

std::int64_t um(double mm) {
  return static_cast<std::int64_t>(std::clamp(std::llround(mm * 1000.0), -2147483648LL, 2147483647LL));
}

}  // namespace

std::vector<std::uint16_t> trace_file(const AxisTrace& t) {
  std::vector<std::uint16_t> out(kTraceHeaderWords + kTraceSampleWords * t.count, 0);
  out[0] = static_cast<std::uint16_t>(t.count);
  out[1] = static_cast<std::uint16_t>(std::min(65535.0, std::round(t.interval_s * 1e4)));
  put32(out, 2, t.reference_time_s ? std::llround(*t.reference_time_s * 1000) : 0xFFFFFFFFLL);
  put32(out, 4, t.reference_time_s ? um(t.reference_mm) : 0);
  out[6] = static_cast<std::uint16_t>(t.alarm.code);
  out[7] = static_cast<std::uint16_t>(t.alarm.phase);
  put32(out, 8, std::llround(t.duration_s * 1000));
  for (std::size_t i = 0; i < t.count; ++i) {
    const TraceSample& s = t.samples[i];
    const std::size_t at = kTraceHeaderWords + kTraceSampleWords * i;
    put32(out, at, std::llround(s.time_s * 1000));
    out[at + 2] = static_cast<std::uint16_t>(s.phase);
    put32(out, at + 3, um(s.motor_mm + t.offset_mm));
    put32(out, at + 5, um(s.velocity_mm_per_s));
    out[at + 7] = s.sensor ? 1 : 0;
  }
  return out;
}

}  // namespace server
