#include "tests/support/process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "tests/support/temp_dir.hpp"

extern char** environ;

namespace test_support {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

namespace {

void add_output(posix_spawn_file_actions_t& fa, int fd, const Output& o, int pipe_write_end) {
  switch (o.to) {
    case Output::To::inherit: break;
    case Output::To::null: posix_spawn_file_actions_addopen(&fa, fd, "/dev/null", O_WRONLY, 0); break;
    case Output::To::file:
      posix_spawn_file_actions_addopen(&fa, fd, o.path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
      break;
    case Output::To::file_append:
      posix_spawn_file_actions_addopen(&fa, fd, o.path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0600);
      break;
    case Output::To::pipe: posix_spawn_file_actions_adddup2(&fa, pipe_write_end, fd); break;
  }
}

}  // namespace

Spawned spawn(const std::vector<std::string>& argv, const Output& out, const Output& err) {
  if (err.to == Output::To::pipe) throw std::invalid_argument("spawn: only stdout can go to a pipe");
  int fds[2] = {-1, -1};
  if (out.to == Output::To::pipe && ::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  add_output(fa, 1, out, fds[1]);
  add_output(fa, 2, err, fds[1]);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  Spawned s;
  const int rc = ::posix_spawnp(&s.pid, args[0], &fa, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (fds[1] >= 0) ::close(fds[1]);
  if (rc != 0) {
    if (fds[0] >= 0) ::close(fds[0]);
    throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(rc));
  }
  s.stdout_fd = fds[0];
  return s;
}

std::optional<int> wait_exit(pid_t pid, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    int status = 0;
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) return status;
    if (r < 0 && errno != EINTR) return std::nullopt;
    if (Clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(5ms);
  }
}

std::optional<int> end_process(pid_t pid, int sig, std::chrono::milliseconds timeout) {
  if (pid <= 0) return std::nullopt;
  ::kill(pid, sig);
  if (auto st = wait_exit(pid, timeout)) return st;
  ::kill(pid, SIGKILL);
  (void)wait_exit(pid, 5s);
  return std::nullopt;
}

std::optional<std::string> wait_for_line(int fd, std::string_view needle, std::chrono::milliseconds timeout,
                                         std::string& got) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    const int left =
        static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count());
    if (::poll(&p, 1, std::max(1, std::min(left, 200))) <= 0) continue;
    char buf[512];
    const ssize_t n = ::read(fd, buf, sizeof(buf));
    if (n <= 0) return std::nullopt;
    got.append(buf, static_cast<std::size_t>(n));
    if (auto nl = got.find('\n'); nl != std::string::npos && got.find(needle) != std::string::npos)
      return got.substr(0, nl);
  }
  return std::nullopt;
}

bool RunResult::exited() const { return status >= 0 && WIFEXITED(status); }
int RunResult::code() const { return exited() ? WEXITSTATUS(status) : -1; }

RunResult run_program(const std::vector<std::string>& argv, std::chrono::milliseconds timeout) {
  TempDir dir;
  const std::string out = dir.file("out"), err = dir.file("err");
  const Spawned child = spawn(argv, Output::file(out), Output::file(err));
  RunResult r;
  if (auto st = wait_exit(child.pid, timeout)) {
    r.status = *st;
  } else {
    ::kill(child.pid, SIGKILL);
    (void)wait_exit(child.pid, 5s);
  }
  r.out = read_file(out);
  r.err = read_file(err);
  return r;
}

bool program_exists(const std::string& name) {
  for (const char* dir : {"/usr/bin/", "/bin/", "/usr/local/bin/", "/usr/sbin/"})
    if (::access((std::string(dir) + name).c_str(), X_OK) == 0) return true;
  return false;
}

}  // namespace test_support
