#pragma once
// Child processes a test starts, and only those: spawned with posix_spawn,
// waited for and ended by PID, every wait bounded in time.
#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace test_support {

// Where a child's stdout or stderr goes.
struct Output {
  enum class To { inherit, null, file, file_append, pipe };
  To to = To::inherit;
  std::string path;  // for file and file_append

  static Output inherit() { return {}; }
  static Output null() { return {To::null, {}}; }
  static Output file(std::string path) { return {To::file, std::move(path)}; }
  static Output append_to(std::string path) { return {To::file_append, std::move(path)}; }
  static Output pipe() { return {To::pipe, {}}; }
};

struct Spawned {
  pid_t pid = -1;
  int stdout_fd = -1;  // the read end when stdout went to Output::pipe(); the caller closes it
};

// Starts argv[0] (looked up in PATH when it has no '/') with stdin from
// /dev/null. Throws when it cannot be started.
Spawned spawn(const std::vector<std::string>& argv, const Output& out, const Output& err);

// Waits for pid to exit within timeout: its waitpid status, or nullopt if it
// is still running.
std::optional<int> wait_exit(pid_t pid, std::chrono::milliseconds timeout);

// Ends a process this test started: signal, wait; SIGKILL if it does not go.
// The waitpid status, or nullopt when it had to be killed.
std::optional<int> end_process(pid_t pid, int sig, std::chrono::milliseconds timeout);

// Reads fd until a whole line containing `needle` arrived, EOF, or the
// deadline: that line, or nullopt. `got` is everything read.
std::optional<std::string> wait_for_line(int fd, std::string_view needle, std::chrono::milliseconds timeout,
                                         std::string& got);

struct RunResult {
  int status = -1;  // waitpid status; -1 when it timed out (and was killed)
  std::string out, err;
  bool exited() const;
  int code() const;
};

// Runs a program to completion (bounded), capturing stdout and stderr.
RunResult run_program(const std::vector<std::string>& argv, std::chrono::milliseconds timeout);

bool program_exists(const std::string& name);

}  // namespace test_support
