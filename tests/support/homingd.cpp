#include "tests/support/homingd.hpp"

#include <signal.h>
#include <unistd.h>

#include <stdexcept>

#include "tests/support/ports.hpp"
#include "tests/support/process.hpp"

namespace test_support {

using namespace std::chrono_literals;

Homingd::Homingd(DaemonOptions options) : options_(std::move(options)), dir_(options_.temp_prefix) {
  if (options_.program.empty()) throw std::invalid_argument("Homingd: no program to start");
  if (options_.db.empty()) options_.db = dir_.file("settings.db");
  std::string last_error;
  for (int attempt = 0; attempt < 5; ++attempt) {
    port_ = !options_.tcp ? 0 : options_.port != 0 ? options_.port : free_port();
    tls_port_ = options_.tls.empty() ? 0 : free_port();
    if (try_start(last_error)) return;
  }
  throw std::runtime_error("homingd did not start: " + last_error);
}

Homingd::~Homingd() {
  if (pid_ > 0) (void)end_process(pid_, SIGKILL, 5s);
  if (out_fd_ >= 0) ::close(out_fd_);
}

std::optional<int> Homingd::stop(int sig, std::chrono::milliseconds timeout) {
  if (pid_ <= 0) return std::nullopt;
  auto st = end_process(pid_, sig, timeout);
  pid_ = -1;
  return st;
}

bool Homingd::try_start(std::string& error) {
  std::vector<std::string> argv = options_.wrapper;
  argv.push_back(options_.program);
  if (options_.tcp) {
    argv.push_back("--tcp");
    argv.push_back("127.0.0.1:" + std::to_string(port_));
  } else {
    argv.push_back("--no-tcp");
  }
  argv.insert(argv.end(), {"--db", options_.db, "--time-scale", std::to_string(options_.time_scale)});
  argv.insert(argv.end(), options_.extra.begin(), options_.extra.end());
  if (!options_.tls.empty()) {
    argv.insert(argv.end(), {"--tls", "127.0.0.1:" + std::to_string(tls_port_)});
    argv.insert(argv.end(), options_.tls.begin(), options_.tls.end());
  }

  const Spawned child = spawn(argv, Output::pipe(), Output::append_to(log_path()));
  std::string got;
  if (auto line = wait_for_line(child.stdout_fd, "listening", options_.start_timeout, got)) {
    line_ = *line;
    pid_ = child.pid;
    out_fd_ = child.stdout_fd;
    return true;
  }
  ::close(child.stdout_fd);
  const auto st = end_process(child.pid, SIGKILL, 5s);
  error = "no `listening` line (stdout: '" + got + "', status " + (st ? std::to_string(*st) : "?") +
          ", log: " + log() + ")";
  return false;
}

}  // namespace test_support
