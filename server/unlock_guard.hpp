#pragma once
// The unlock code's guard against guessing: after a few wrong codes in a row
// every unlock is refused, for the whole module, for a while that doubles with
// each further wrong code up to a cap. While locked out a written code is not
// even compared (the answer cannot depend on it: no timing oracle), so the
// right code is refused too. Pure: the caller passes the time (the runtime's
// steady clock, a test's hand-driven one).
#include <chrono>
#include <cstdint>

namespace server {

struct UnlockPolicy {
  std::uint32_t free_wrong_codes = 5;  // wrong codes in a row before the first lockout
  std::chrono::seconds first_lockout{10};
  std::chrono::seconds max_lockout{900};
};

enum class UnlockVerdict { right, wrong, locked_out };

class UnlockGuard {
 public:
  using Clock = std::chrono::steady_clock;

  struct Outcome {
    UnlockVerdict verdict = UnlockVerdict::wrong;
    // A wrong code that began a lockout: how long, after how many in a row.
    bool lockout_started = false;
    std::chrono::seconds lockout{0};
    std::uint32_t wrong_in_a_row = 0;
  };

  // code 0: no code configured, every attempt is wrong.
  UnlockGuard(std::uint32_t code, UnlockPolicy policy) : code_(code), policy_(policy) {}

  // What attempt() would answer, without counting anything (the write path
  // decides before it acts: server/write_plan.hpp). A wrong code's outcome
  // (the count it makes, the lockout it begins) comes with it.
  Outcome judge(std::uint32_t written, Clock::time_point now) const;
  // Judges and records: a wrong code counts, a right one clears the count.
  Outcome attempt(std::uint32_t written, Clock::time_point now);
  // Whole seconds left of the lockout, rounded up; 0 when codes are compared.
  std::chrono::seconds remaining(Clock::time_point now) const;
  std::uint32_t wrong_in_a_row() const { return wrong_in_a_row_; }
  bool configured() const { return code_ != 0; }
  // The lockout the n-th wrong code in a row begins (0 s below free_wrong_codes).
  std::chrono::seconds lockout_after(std::uint32_t wrong_in_a_row) const;

 private:
  std::uint32_t code_;
  UnlockPolicy policy_;
  std::uint32_t wrong_in_a_row_ = 0;
  Clock::time_point locked_until_{};
};

}  // namespace server
