#include "poll_window.hpp"

#include <algorithm>

namespace server {

void PollWindow::waited(std::chrono::nanoseconds wait, bool caught) {
  if (caught || longest_ <= Micros{0}) return;
  if (wait <= longest_) {
    window_ = std::min(longest_, std::max(kFirstStep, window_ * 2));
    return;
  }
  window_ /= 2;
  if (window_ < kFirstStep) window_ = Micros{0};
}

}  // namespace server
