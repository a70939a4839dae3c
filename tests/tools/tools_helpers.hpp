#pragma once
// Running homingctl against a Daemon (tests/server/daemon.hpp, tests/support).
#include <nlohmann/json.hpp>

#include "daemon.hpp"

#ifndef HOMINGCTL_PATH
#error "HOMINGCTL_PATH must be defined"
#endif

namespace tools_test {

using namespace e2e;

inline RunResult ctl(const Daemon& d, std::vector<std::string> args, std::chrono::milliseconds timeout = 60s) {
  std::vector<std::string> argv{HOMINGCTL_PATH, "--tcp", "127.0.0.1:" + std::to_string(d.port())};
  argv.insert(argv.end(), args.begin(), args.end());
  return run_program(argv, timeout);
}

inline RunResult ctl_plain(std::vector<std::string> args, std::chrono::milliseconds timeout = 30s) {
  args.insert(args.begin(), HOMINGCTL_PATH);
  return run_program(args, timeout);
}

inline nlohmann::json json_of(const RunResult& r) {
  try {
    return nlohmann::json::parse(r.out);
  } catch (const std::exception& e) {
    FAIL("not JSON: " << e.what() << "\nstdout: " << r.out << "\nstderr: " << r.err);
  }
  return {};
}

#define SHOW(r) INFO("exit " << (r).code() << "\nstdout:\n" << (r).out << "\nstderr:\n" << (r).err)

// How often `what` occurs in `s` (overlapping occurrences counted).
inline std::size_t count_of(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (auto at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
  return n;
}

}  // namespace tools_test
