#pragma once
// A homingd this process starts: on a free loopback port with a database in
// its own temporary directory, ready once it printed its `listening` line,
// stopped by PID with SIGTERM (at the latest when the object goes), as a
// service manager stops it: so that its exit runs, and with it LeakSanitizer
// in a sanitized build. Its stderr, where sanitizer reports go, is the log.
#include <signal.h>
#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "tests/support/temp_dir.hpp"

namespace test_support {

struct DaemonOptions {
  std::string program;               // the homingd to run (the tests' Daemon fills in the build's)
  std::vector<std::string> wrapper;  // runs homingd through this command (setpriv ...)
  int port = 0;                      // 0: a free port chosen for each attempt
  std::string db;                    // empty: a fresh database in the daemon's temp dir
  double time_scale = 10;
  std::vector<std::string> extra;    // more options (--rtu ..., --max-clients ...)
  // Not empty: Modbus/TCP Security too, --tls 127.0.0.1:<a free port> followed
  // by these options (tls_server_options() of tests/support/test_pki.hpp).
  std::vector<std::string> tls;
  bool tcp = true;
  std::chrono::milliseconds start_timeout = std::chrono::seconds(10);
  std::string temp_prefix = "homingd";  // name of its temporary directory
};

// Long enough for a sanitized homingd to exit and run its leak check.
inline constexpr std::chrono::milliseconds kStopTimeout = std::chrono::seconds(20);

// The lines of a log that begin a sanitizer report (ASan, LSan, UBSan).
std::vector<std::string> sanitizer_reports(const std::string& log);

class Homingd {
 public:
  // Throws with homingd's output and log when it does not start (five tries:
  // the free port may be taken by someone else in between).
  explicit Homingd(DaemonOptions options);
  ~Homingd();
  Homingd(const Homingd&) = delete;
  Homingd& operator=(const Homingd&) = delete;

  int port() const { return port_; }
  int tls_port() const { return tls_port_; }
  pid_t pid() const { return pid_; }
  const std::string& db() const { return options_.db; }
  const std::string& listening_line() const { return line_; }
  std::string log() const { return read_file(log_path()); }
  std::string log_path() const { return dir_.file("homingd.log"); }
  bool running() const { return pid_ > 0; }
  // Leaves the temporary directory (database, log) in place for a post-mortem.
  void keep_files() { dir_.keep(); }

  // Stops it by PID; the waitpid status, or nullopt if it had to be killed.
  // Stopping it with SIGKILL is how a test says it means to kill it.
  std::optional<int> stop(int sig = SIGTERM, std::chrono::milliseconds timeout = kStopTimeout);

  // Stops it with SIGTERM if it still runs, then says what was wrong with its
  // end: an exit other than 0 (not checked after stop(SIGKILL)) or a
  // sanitizer report in its log, with the log's relevant part. Empty: none.
  std::string shutdown_problems();

 private:
  bool try_start(std::string& error);

  DaemonOptions options_;
  TempDir dir_;
  int port_ = 0;
  int tls_port_ = 0;
  pid_t pid_ = -1;
  bool stopped_ = false;
  int stop_signal_ = 0;
  std::optional<int> status_;  // waitpid status after stop(); nullopt: killed or lost
  int out_fd_ = -1;  // kept open: homingd's stdout never sees a closed pipe
  std::string line_;
};

}  // namespace test_support
