#pragma once
// The last true sensor edges of one axis, for tests and the trace.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace homing::sim {

struct EdgeRecord {
  std::size_t axis = 0;
  double time_s = 0;  // simulator time
  bool to_active = false;
  double actual_mm = 0;  // where this carriage was at the edge
  double motor_mm = 0;   // where the step output that drives it was (carriage - slip)
  std::size_t output = 0;  // that output: the axis itself, or its commutator master
};

class EdgeRing {
 public:
  static constexpr std::size_t kCapacity = 64;
  void push(const EdgeRecord& e) { items_[total_++ % kCapacity] = e; }
  std::uint64_t total() const { return total_; }
  std::size_t size() const { return static_cast<std::size_t>(std::min<std::uint64_t>(total_, kCapacity)); }
  // i = 0 is the oldest kept.
  const EdgeRecord& at(std::size_t i) const { return items_[(total_ - size() + i) % kCapacity]; }
  std::optional<EdgeRecord> last(std::optional<bool> to_active = std::nullopt) const {
    for (std::size_t i = size(); i-- > 0;) {
      if (!to_active || at(i).to_active == *to_active) return at(i);
    }
    return std::nullopt;
  }
  std::size_t copy(std::span<EdgeRecord> out) const {
    const std::size_t n = std::min(out.size(), size());
    for (std::size_t i = 0; i < n; ++i) out[i] = at(size() - n + i);
    return n;
  }

 private:
  std::array<EdgeRecord, kCapacity> items_{};
  std::uint64_t total_ = 0;
};

}  // namespace homing::sim
