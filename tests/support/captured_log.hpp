#pragma once
// The log lines written while it lives: a ring-buffer sink beside the default
// logger's own, removed again when it goes.
#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

namespace test_support {

struct CapturedLog {
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> sink = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(500);
  CapturedLog() { spdlog::default_logger()->sinks().push_back(sink); }
  ~CapturedLog() { std::erase(spdlog::default_logger()->sinks(), sink); }
  CapturedLog(const CapturedLog&) = delete;
  CapturedLog& operator=(const CapturedLog&) = delete;
  std::vector<std::string> lines() const { return sink->last_formatted(); }
  std::string text() const {
    std::string all;
    for (const std::string& line : sink->last_formatted()) all += line;
    return all;
  }
};

}  // namespace test_support
