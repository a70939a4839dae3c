#include "inputs.hpp"

#include <algorithm>

#include "event_clock.hpp"

namespace homing::gpiod {

std::expected<void, std::string> EdgeInput::poll(std::int64_t now_mono, std::int64_t now_real) {
  // The value is read before draining: when the queue is empty it is the
  // level at the drain, so a change without an event (a lost event) is
  // still seen, and an event after it cannot be mistaken for one.
  auto value = lines_.get_value(line_);
  if (!value) return std::unexpected(value.error());
  LineEvent buf[16];
  std::size_t total = 0;
  for (;;) {
    auto got = lines_.read_events(line_, buf);
    if (!got) return std::unexpected(got.error());
    const std::size_t n = *got;
    for (std::size_t i = 0; i < n; ++i)
      pending_.push_back({to_monotonic_ns(buf[i].timestamp_ns, now_mono, now_real), buf[i].rising});
    total += n;
    if (n < std::size(buf)) break;
  }
  if (total == 0 && pending_.empty() && *value != level_) pending_.push_back({-1, *value});
  return {};
}

void EdgeInput::take(std::int64_t start_ns, std::int64_t end_ns, bool rising_only, InputEdges& edges, bool& level) {
  std::size_t used = 0;
  for (; used < pending_.size(); ++used) {
    const Pending& p = pending_[used];
    if (p.time_ns >= end_ns) break;
    if (p.level == level_) continue;
    level_ = p.level;
    // time -1: a change seen only in the level; the engine places it mid-period.
    if (p.time_ns < 0) continue;
    if (rising_only && !p.level) continue;
    const double t_s = static_cast<double>(std::clamp(p.time_ns, start_ns, end_ns) - start_ns) * 1e-9;
    edges.add(t_s);
  }
  pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(used));
  level = level_;
}

std::expected<bool, std::string> LevelInput::sample(std::int64_t now_ns) {
  // Drained first, so the descriptor no longer wakes the loop for what this
  // read sees; an edge after the drain leaves it readable for the next one.
  LineEvent discarded[16];
  while (events_) {
    auto got = lines_.read_events(line_, discarded);
    if (!got) return std::unexpected(got.error());
    if (*got < std::size(discarded)) break;
  }
  auto v = lines_.get_value(line_);
  if (!v) return std::unexpected(v.error());
  if (*v != raw_) {
    raw_ = *v;
    raw_since_ns_ = now_ns;
  }
  if (raw_ != stable_ && now_ns - raw_since_ns_ >= debounce_ns_) stable_ = raw_;
  return stable_;
}

}  // namespace homing::gpiod
