#include "recurring_warning.hpp"

#include <spdlog/spdlog.h>

namespace server {

void RecurringWarning::failed(std::int64_t now_ms, const std::string& message) {
  ++attempts_;
  if (since_ms_ < 0) {
    since_ms_ = last_line_ms_ = now_ms;
    attempts_ = 1;
    last_message_ = message;
    spdlog::warn("{}: {}", failing_, message);
    return;
  }
  if (message == last_message_ && now_ms - last_line_ms_ < repeat_ms_) return;
  spdlog::warn("{}: {} (still failing: {} attempts in {} s)", failing_, message, attempts_, (now_ms - since_ms_) / 1000);
  last_line_ms_ = now_ms;
  last_message_ = message;
}

void RecurringWarning::worked(std::int64_t now_ms) {
  if (since_ms_ < 0) return;
  spdlog::info("{} after {} failed attempts in {} s", recovered_, attempts_, (now_ms - since_ms_) / 1000);
  since_ms_ = -1;
  attempts_ = 0;
  last_message_.clear();
}

}  // namespace server
