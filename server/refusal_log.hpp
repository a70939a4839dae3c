#pragma once
// Refused requests in the log without flooding it: the first refusal of a
// client for a reason is written out whole; while that client keeps being
// refused for that reason, the rest are counted and written as one line per
// client and reason per interval. A client quiet for a whole interval is
// forgotten: its next refusal is written out whole again. Pure: the caller
// passes the time; the lines go to a sink (spdlog in the daemon, a vector in
// tests).
#include <spdlog/common.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>

namespace server {

class RefusalLog {
 public:
  using Clock = std::chrono::steady_clock;
  using Sink = std::function<void(spdlog::level::level_enum, const std::string&)>;

  // what: "writes", "connections": the noun of the summary line.
  RefusalLog(std::string what, std::chrono::seconds interval, Sink sink);

  // client: who ("tcp 127.0.0.1"); reason: why, as the summary names it
  // ("reason 9 (wrong_unlock_code)"); line: the whole line for the first one.
  void refused(const std::string& client, const std::string& reason, spdlog::level::level_enum level,
               const std::string& line, Clock::time_point now);
  // Writes the counts of an interval that has passed (call it now and then).
  void flush(Clock::time_point now);
  // Writes every count not yet written, the interval passed or not (on the way out).
  void flush_all(Clock::time_point now);
  // Clients whose counts or whose quiet interval flush() still has to see.
  bool holds_clients() const { return !active_.empty(); }

 private:
  struct Counted {
    std::uint64_t not_logged = 0;  // refusals of this interval not written out
    spdlog::level::level_enum level = spdlog::level::warn;
  };
  std::string what_;
  std::chrono::seconds interval_;
  Sink sink_;
  Clock::time_point interval_start_{};
  bool started_ = false;
  std::map<std::pair<std::string, std::string>, Counted> active_;
  void write_counts(Clock::time_point now);
};

}  // namespace server
