#pragma once
// Per-axis trace of the last homing cycle: one sample per control period
// (halving the rate when the buffer fills, so a long cycle is still whole),
// published when the cycle ends. Read over Modbus with function 20 (read file
// record): file number = axis + 1 (1 = X ... 6 = C), records = registers:
//   0      sample count            5  (reserved)
//   1      sample interval, 0.1 ms  6  alarm code (0 = none)
//   2..3   reference edge time, ms (u32, 0xFFFFFFFF = none)
//   4..5   reference edge position, µm (i32), final machine coordinates
//   7      alarm phase             8..9 cycle duration, ms (u32)
//   10 + 8·i: sample i: time ms (u32), phase, position µm (i32, final machine
//   coordinates), velocity µm/s (i32), sensor (0/1)
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "homing/status.hpp"

namespace server {

inline constexpr std::size_t kTraceHeaderWords = 10;
inline constexpr std::size_t kTraceSampleWords = 8;
inline constexpr std::size_t kTraceCapacity = 1200;  // 10 + 8·1200 < 10000 records per file

// Trivial, so that the buffers below can be left unwritten until a cycle
// fills them: a new control loop would otherwise write 0.6 MB it may never use.
struct TraceSample {
  double time_s;
  homing::Phase phase;
  double motor_mm;
  double velocity_mm_per_s;
  bool sensor;
};

struct AxisTrace {
  std::array<TraceSample, kTraceCapacity> samples;  // [0, count) are written; nothing reads past count
  std::size_t count = 0;
  double interval_s = 0;           // between kept samples
  std::optional<double> reference_time_s;
  double reference_mm = 0;         // final machine coordinates
  double offset_mm = 0;            // machine = motor + offset, at the end
  homing::Alarm alarm{};
  double duration_s = 0;
};

// Fixed-size recorder the control loop writes into; no allocation.
class TraceRecorder {
 public:
  void begin(double period_s);
  // One control period of a running cycle; motor positions from the outputs.
  void record(double time_s, const homing::Status& status, const std::array<double, homing::kAxisCount>& motor_mm);
  // The cycle ended: fills in references and alarms, and keeps the last
  // recorded period even when the halved rate skipped it, so the trace ends
  // where the axes came to rest.
  void finish(double time_s, const homing::Status& status, const std::array<double, homing::kAxisCount>& motor_mm);
  const std::array<AxisTrace, homing::kAxisCount>& traces() const { return traces_; }
  bool active() const { return active_; }

 private:
  void keep_latest();

  std::array<AxisTrace, homing::kAxisCount> traces_;  // default-initialised: see TraceSample
  std::array<TraceSample, homing::kAxisCount> latest_{};  // the last recorded period
  bool latest_kept_ = true;
  std::array<bool, homing::kAxisCount> involved_{};
  double start_s_ = 0;
  double period_s_ = 0.001;
  std::size_t stride_ = 1;
  std::uint64_t tick_ = 0;
  bool active_ = false;
};

// The FC 20 file of one axis as 16-bit registers, high word first for 32-bit values.
std::vector<std::uint16_t> trace_file(const AxisTrace& trace);

}  // namespace server
