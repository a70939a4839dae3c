#pragma once
// A warning for a housekeeping step that fails again at every look (a full
// disk fails the settings backup twice a second): said when it starts, then
// at most once a minute with how often it failed meanwhile (at once when the
// reason changes), and once more when the step works again. The journal says
// when it began and when it ended, without a line per attempt.
#include <cstdint>
#include <string>
#include <utility>

namespace server {

class RecurringWarning {
 public:
  // failing: "settings backup not written"; recovered: "settings backup written again".
  RecurringWarning(std::string failing, std::string recovered, std::int64_t repeat_ms = 60'000)
      : failing_(std::move(failing)), recovered_(std::move(recovered)), repeat_ms_(repeat_ms) {}

  // One attempt at now_ms: failed with message, or worked.
  void failed(std::int64_t now_ms, const std::string& message);
  void worked(std::int64_t now_ms);
  bool failing() const { return since_ms_ >= 0; }

 private:
  std::string failing_;
  std::string recovered_;
  std::int64_t repeat_ms_;
  std::int64_t since_ms_ = -1;      // the first failure of this stretch; -1: working
  std::int64_t last_line_ms_ = 0;
  std::uint64_t attempts_ = 0;      // failed attempts in this stretch
  std::string last_message_;
};

}  // namespace server
