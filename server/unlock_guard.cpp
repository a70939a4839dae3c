#include "unlock_guard.hpp"

#include <algorithm>

namespace server {

std::chrono::seconds UnlockGuard::lockout_after(std::uint32_t wrong) const {
  if (wrong < policy_.free_wrong_codes || policy_.free_wrong_codes == 0) return std::chrono::seconds{0};
  // Doubling from the first lockout; past 30 doublings any cap is reached.
  const std::uint32_t doublings = std::min<std::uint32_t>(wrong - policy_.free_wrong_codes, 30);
  const std::chrono::seconds grown = policy_.first_lockout * (std::int64_t{1} << doublings);
  return std::min(grown, std::max(policy_.max_lockout, policy_.first_lockout));
}

UnlockGuard::Outcome UnlockGuard::judge(std::uint32_t written, Clock::time_point now) const {
  Outcome out;
  if (now < locked_until_) {
    out.verdict = UnlockVerdict::locked_out;
    out.wrong_in_a_row = wrong_in_a_row_;
    return out;
  }
  // Every bit looked at whatever the value: the time of the answer says nothing.
  const bool right = code_ != 0 && ((written ^ code_) == 0);
  if (right) {
    out.verdict = UnlockVerdict::right;
    return out;
  }
  out.verdict = UnlockVerdict::wrong;
  out.wrong_in_a_row = wrong_in_a_row_ < UINT32_MAX ? wrong_in_a_row_ + 1 : wrong_in_a_row_;
  out.lockout = lockout_after(out.wrong_in_a_row);
  out.lockout_started = out.lockout.count() > 0;
  return out;
}

UnlockGuard::Outcome UnlockGuard::attempt(std::uint32_t written, Clock::time_point now) {
  const Outcome out = judge(written, now);
  switch (out.verdict) {
    case UnlockVerdict::locked_out: break;
    case UnlockVerdict::right: wrong_in_a_row_ = 0; break;
    case UnlockVerdict::wrong:
      wrong_in_a_row_ = out.wrong_in_a_row;
      if (out.lockout_started) locked_until_ = now + out.lockout;
      break;
  }
  return out;
}

std::chrono::seconds UnlockGuard::remaining(Clock::time_point now) const {
  if (now >= locked_until_) return std::chrono::seconds{0};
  return std::chrono::ceil<std::chrono::seconds>(locked_until_ - now);
}

}  // namespace server
