#include "refusal_log.hpp"

#include <fmt/format.h>

namespace server {

RefusalLog::RefusalLog(std::string what, std::chrono::seconds interval, Sink sink)
    : what_(std::move(what)), interval_(interval), sink_(std::move(sink)) {}

void RefusalLog::refused(const std::string& client, const std::string& reason, spdlog::level::level_enum level,
                         const std::string& line, Clock::time_point now) {
  flush(now);
  auto [it, first] = active_.try_emplace({client, reason}, Counted{0, level});
  if (first) {
    sink_(level, line);
  } else {
    ++it->second.not_logged;
  }
}

void RefusalLog::flush(Clock::time_point now) {
  if (!started_) {
    interval_start_ = now;
    started_ = true;
    return;
  }
  if (now - interval_start_ < interval_) return;
  write_counts(now);
}

void RefusalLog::flush_all(Clock::time_point now) {
  if (started_) write_counts(now);
}

void RefusalLog::write_counts(Clock::time_point now) {
  const auto seconds = std::chrono::duration_cast<std::chrono::seconds>(now - interval_start_).count();
  for (auto it = active_.begin(); it != active_.end();) {
    if (it->second.not_logged == 0) {
      it = active_.erase(it);  // quiet for an interval: the next one is written out whole
      continue;
    }
    sink_(it->second.level,
          fmt::format("{}: {} more {} refused, {}, in the last {} s (one line per client and reason every {} s)",
                      it->first.first, it->second.not_logged, what_, it->first.second, seconds, interval_.count()));
    it->second.not_logged = 0;
    ++it;
  }
  interval_start_ = now;
}

}  // namespace server
