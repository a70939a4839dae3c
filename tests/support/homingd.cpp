#include "tests/support/homingd.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "tests/support/ports.hpp"
#include "tests/support/process.hpp"

namespace test_support {

using namespace std::chrono_literals;

namespace {

// How each sanitizer's report begins (UBSan: "file:line:col: runtime error: ...").
constexpr std::array<std::string_view, 6> kReportMarks{
    "ERROR: AddressSanitizer", "ERROR: LeakSanitizer",       "SUMMARY: AddressSanitizer",
    "SUMMARY: LeakSanitizer",  "SUMMARY: UndefinedBehaviorSanitizer", "runtime error:",
};

std::string describe(const std::optional<int>& status) {
  if (!status) return "did not end on its own (killed, or its status was already taken)";
  if (WIFEXITED(*status)) return "exited " + std::to_string(WEXITSTATUS(*status));
  if (WIFSIGNALED(*status))
    return "ended by signal " + std::to_string(WTERMSIG(*status)) + " (" + strsignal(WTERMSIG(*status)) + ")";
  return "waitpid status " + std::to_string(*status);
}

// At most `limit` characters of the log: from the first report on when there
// is one (the reports come last, with their stacks), else its end.
std::string excerpt(const std::string& log, std::size_t limit) {
  std::size_t from = std::string::npos;
  for (const auto mark : kReportMarks) from = std::min(from, log.find(mark));
  if (from != std::string::npos) {
    from = log.rfind('\n', from);
    from = from == std::string::npos ? 0 : from + 1;
    return log.substr(from, limit);
  }
  return log.size() <= limit ? log : "[...]" + log.substr(log.size() - limit);
}

}  // namespace

std::vector<std::string> sanitizer_reports(const std::string& log) {
  std::vector<std::string> out;
  std::istringstream in(log);
  std::string line;
  while (std::getline(in, line))
    for (const auto mark : kReportMarks)
      if (line.find(mark) != std::string::npos) {
        out.push_back(line);
        break;
      }
  return out;
}

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
  if (pid_ > 0) (void)end_process(pid_, SIGTERM, kStopTimeout);
  if (out_fd_ >= 0) ::close(out_fd_);
}

std::optional<int> Homingd::stop(int sig, std::chrono::milliseconds timeout) {
  if (pid_ <= 0) return std::nullopt;
  status_ = end_process(pid_, sig, timeout);
  stopped_ = true;
  stop_signal_ = sig;
  pid_ = -1;
  return status_;
}

std::string Homingd::shutdown_problems() {
  if (pid_ > 0) (void)stop(SIGTERM);
  if (!stopped_) return {};  // never started
  std::string problems;
  const bool clean = status_ && WIFEXITED(*status_) && WEXITSTATUS(*status_) == 0;
  if (!clean && stop_signal_ != SIGKILL)
    problems += "homingd " + describe(status_) + " after signal " + std::to_string(stop_signal_) +
                ", not a clean exit 0\n";
  const std::string text = log();
  for (const auto& line : sanitizer_reports(text)) problems += "sanitizer report in homingd's stderr: " + line + "\n";
  if (!problems.empty()) {
    dir_.keep();  // the whole log and the database for a post-mortem
    problems += "--- homingd log (" + log_path() + ", kept) ---\n" + excerpt(text, 16000);
  }
  return problems;
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
