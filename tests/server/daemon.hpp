#pragma once
// End-to-end test helpers: start the real homingd (posix_spawn) on a free
// loopback port with a temporary database, wait for its `listening` line,
// stop it by PID; a libmodbus client with named-register helpers built on the
// register table; a raw Modbus/TCP transaction for what libmodbus cannot frame
// (FC 43/14); small process/pty utilities. Everything is bounded in time.
#include <arpa/inet.h>
#include <fcntl.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "registers/codec.hpp"
#include "registers/lookup.hpp"
#include "registers/table.hpp"

#ifndef HOMINGD_PATH
#error "HOMINGD_PATH must be defined to the homingd executable"
#endif

extern char** environ;

namespace e2e {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

inline std::string homingd_path() { return HOMINGD_PATH; }

// ---------------------------------------------------------------- temp dir
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "homingd-e2e-XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::string file(std::string_view name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

inline std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A port that was free a moment ago (bind 127.0.0.1:0, read it, close).
inline int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error("socket failed");
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    ::close(fd);
    throw std::runtime_error("bind failed");
  }
  socklen_t len = sizeof(a);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

// ---------------------------------------------------------------- processes
// Waits for pid to exit within timeout; its exit status (as waitpid gives it)
// or nullopt if it is still running.
inline std::optional<int> wait_exit(pid_t pid, std::chrono::milliseconds timeout) {
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

// Ends a process this test started: signal, wait; SIGKILL if it does not go.
inline std::optional<int> end_process(pid_t pid, int sig, std::chrono::milliseconds timeout) {
  if (pid <= 0) return std::nullopt;
  ::kill(pid, sig);
  if (auto st = wait_exit(pid, timeout)) return st;
  ::kill(pid, SIGKILL);
  (void)wait_exit(pid, 5s);
  return std::nullopt;
}

struct RunResult {
  int status = -1;  // waitpid status; -1 when it timed out (and was killed)
  std::string out, err;
  bool exited() const { return status >= 0 && WIFEXITED(status); }
  int code() const { return exited() ? WEXITSTATUS(status) : -1; }
};

// Runs a program to completion (bounded), capturing stdout and stderr into files.
inline RunResult run_program(const std::vector<std::string>& argv, std::chrono::milliseconds timeout) {
  TempDir dir;
  const std::string out = dir.file("out"), err = dir.file("err");
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = -1;
  const int rc = ::posix_spawnp(&pid, args[0], &fa, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(rc));
  RunResult r;
  if (auto st = wait_exit(pid, timeout)) {
    r.status = *st;
  } else {
    ::kill(pid, SIGKILL);
    (void)wait_exit(pid, 5s);
  }
  r.out = read_file(out);
  r.err = read_file(err);
  return r;
}

inline bool program_exists(const std::string& name) {
  for (const char* dir : {"/usr/bin/", "/bin/", "/usr/local/bin/", "/usr/sbin/"})
    if (::access((std::string(dir) + name).c_str(), X_OK) == 0) return true;
  return false;
}

// ---------------------------------------------------------------- homingd
struct DaemonOptions {
  std::string program;               // empty: the build's homingd
  std::vector<std::string> wrapper;  // runs homingd through this command (setpriv ...)
  int port = 0;                      // 0: a free port chosen for each attempt
  std::string db;                    // empty: a fresh database in the daemon's temp dir
  double time_scale = 10;
  std::vector<std::string> extra;    // more options (--rtu ..., --max-clients ...)
  bool tcp = true;
  std::chrono::milliseconds start_timeout = 10s;
};

class Daemon {
 public:
  explicit Daemon(DaemonOptions options = {}) : options_(std::move(options)) {
    if (options_.db.empty()) options_.db = dir_.file("settings.db");
    std::string last_error;
    // The port was free when chosen; another process may take it first: retry.
    for (int attempt = 0; attempt < 5; ++attempt) {
      port_ = !options_.tcp ? 0 : options_.port != 0 ? options_.port : free_port();
      if (try_start(last_error)) return;
    }
    throw std::runtime_error("homingd did not start: " + last_error);
  }
  ~Daemon() {
    if (pid_ > 0) (void)end_process(pid_, SIGKILL, 5s);
    if (out_fd_ >= 0) ::close(out_fd_);
  }
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  int port() const { return port_; }
  pid_t pid() const { return pid_; }
  const std::string& db() const { return options_.db; }
  const std::string& listening_line() const { return line_; }
  std::string log() const { return read_file(log_path()); }
  std::string log_path() const { return dir_.file("homingd.log"); }
  bool running() const { return pid_ > 0; }

  // Stops it by PID; the waitpid status, or nullopt if it had to be killed.
  std::optional<int> stop(int sig = SIGTERM, std::chrono::milliseconds timeout = 15s) {
    if (pid_ <= 0) return std::nullopt;
    auto st = end_process(pid_, sig, timeout);
    pid_ = -1;
    return st;
  }

 private:
  bool try_start(std::string& error) {
    std::vector<std::string> argv = options_.wrapper;
    argv.push_back(options_.program.empty() ? homingd_path() : options_.program);
    if (options_.tcp) {
      argv.push_back("--tcp");
      argv.push_back("127.0.0.1:" + std::to_string(port_));
    } else {
      argv.push_back("--no-tcp");
    }
    argv.insert(argv.end(), {"--db", options_.db, "--time-scale", std::to_string(options_.time_scale)});
    argv.insert(argv.end(), options_.extra.begin(), options_.extra.end());

    int pipe_fds[2];
    if (::pipe2(pipe_fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&fa, pipe_fds[1], 1);
    posix_spawn_file_actions_addopen(&fa, 2, log_path().c_str(), O_WRONLY | O_CREAT | O_APPEND, 0600);
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    pid_t pid = -1;
    const int rc = ::posix_spawn(&pid, args[0], &fa, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    ::close(pipe_fds[1]);
    if (rc != 0) {
      ::close(pipe_fds[0]);
      throw std::runtime_error("cannot spawn " + argv[0] + ": " + std::strerror(rc));
    }
    // Wait for the one stdout line that says `listening`.
    std::string got;
    const auto deadline = Clock::now() + options_.start_timeout;
    bool ready = false, eof = false;
    while (!ready && !eof && Clock::now() < deadline) {
      pollfd p{pipe_fds[0], POLLIN, 0};
      const int left = static_cast<int>(
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count());
      if (::poll(&p, 1, std::max(1, std::min(left, 200))) <= 0) continue;
      char buf[512];
      const ssize_t n = ::read(pipe_fds[0], buf, sizeof(buf));
      if (n <= 0) {
        eof = true;
        break;
      }
      got.append(buf, static_cast<std::size_t>(n));
      if (auto nl = got.find('\n'); nl != std::string::npos && got.find("listening") != std::string::npos) {
        line_ = got.substr(0, nl);
        ready = true;
      }
    }
    if (ready) {
      pid_ = pid;
      out_fd_ = pipe_fds[0];
      return true;
    }
    ::close(pipe_fds[0]);
    const auto st = end_process(pid, SIGKILL, 5s);
    error = "no `listening` line (stdout: '" + got + "', status " + (st ? std::to_string(*st) : "?") +
            ", log: " + log() + ")";
    return false;
  }

  TempDir dir_;
  DaemonOptions options_;
  int port_ = 0;
  pid_t pid_ = -1;
  int out_fd_ = -1;
  std::string line_;
};

// ---------------------------------------------------------------- registers
inline const registers::Register& reg(std::string_view name) {
  const registers::Register* r = registers::find_register(name);
  if (!r) throw std::runtime_error("no register named " + std::string(name));
  return *r;
}

// Raw value of a length in mm (µm registers).
inline std::int64_t um(double mm) { return static_cast<std::int64_t>(std::llround(mm * 1000.0)); }

// Modbus exception code of the last failed call (0 if it was not an exception).
inline int exception_of(int err) {
  if (err > MODBUS_ENOBASE && err <= EMBXGTAR) return err - MODBUS_ENOBASE;
  return 0;
}

// ---------------------------------------------------------------- client
class Client {
 public:
  static Client tcp(int port, int module_unit = 1, int sim_unit = 247) {
    modbus_t* ctx = modbus_new_tcp("127.0.0.1", port);
    if (!ctx) throw std::runtime_error("modbus_new_tcp failed");
    return Client(ctx, module_unit, sim_unit);
  }
  static Client rtu(const std::string& device, int baud, char parity, int module_unit = 1) {
    modbus_t* ctx = modbus_new_rtu(device.c_str(), baud, parity, 8, 1);
    if (!ctx) throw std::runtime_error("modbus_new_rtu failed");
    return Client(ctx, module_unit, -1);
  }

  Client(Client&& o) noexcept : ctx_(o.ctx_), module_unit_(o.module_unit_), sim_unit_(o.sim_unit_) {
    o.ctx_ = nullptr;
  }
  Client& operator=(Client&&) = delete;
  ~Client() { close(); }

  modbus_t* ctx() const { return ctx_; }
  void close() {
    if (ctx_) {
      modbus_close(ctx_);
      modbus_free(ctx_);
      ctx_ = nullptr;
    }
  }
  void set_timeout(std::chrono::milliseconds t) {
    modbus_set_response_timeout(ctx_, static_cast<std::uint32_t>(t.count() / 1000),
                                static_cast<std::uint32_t>((t.count() % 1000) * 1000));
  }
  void use_unit(int unit) { modbus_set_slave(ctx_, unit); }

  // Reads the raw value of a named register (FC 1/2/3/4 by its table).
  std::int64_t read(std::string_view name) {
    auto v = try_read(name);
    if (!v) throw std::runtime_error("read " + std::string(name) + ": " + modbus_strerror(last_errno_));
    return *v;
  }
  std::optional<std::int64_t> try_read(std::string_view name) {
    const registers::Register& r = reg(name);
    select(r);
    int rc = -1;
    std::uint16_t words[2] = {0, 0};
    std::uint8_t bit = 0;
    switch (r.table) {
      case registers::Table::coil: rc = modbus_read_bits(ctx_, r.address, 1, &bit); break;
      case registers::Table::discrete_input: rc = modbus_read_input_bits(ctx_, r.address, 1, &bit); break;
      case registers::Table::holding_register: rc = modbus_read_registers(ctx_, r.address, r.words(), words); break;
      case registers::Table::input_register:
        rc = modbus_read_input_registers(ctx_, r.address, r.words(), words);
        break;
    }
    if (rc < 0) {
      last_errno_ = errno;
      return std::nullopt;
    }
    if (r.table == registers::Table::coil || r.table == registers::Table::discrete_input) return bit;
    return registers::decode_words(r, std::span<const std::uint16_t>(words, r.words()),
                                   registers::WordOrder::high_first);
  }
  double read_mm(std::string_view name) { return static_cast<double>(read(name)) / 1000.0; }

  // Writes a raw value: coils FC 5, holding registers FC 16 (both words of a
  // 32-bit value in one request). Returns 0 or the Modbus exception code
  // (-1 for a transport error).
  int write(std::string_view name, std::int64_t raw) {
    const registers::Register& r = reg(name);
    select(r);
    int rc = -1;
    if (r.table == registers::Table::coil) {
      rc = modbus_write_bit(ctx_, r.address, raw != 0 ? 1 : 0);
    } else {
      std::uint16_t words[2] = {0, 0};
      registers::encode_words(r, raw, registers::WordOrder::high_first, std::span<std::uint16_t>(words, r.words()));
      rc = modbus_write_registers(ctx_, r.address, r.words(), words);
    }
    if (rc >= 0) return 0;
    last_errno_ = errno;
    const int ex = exception_of(last_errno_);
    return ex ? ex : -1;
  }
  // Like write(), but a failure throws (for set-up steps).
  void set(std::string_view name, std::int64_t raw) {
    const int rc = write(name, raw);
    if (rc != 0)
      throw std::runtime_error("write " + std::string(name) + " = " + std::to_string(raw) + " failed: " +
                               (rc > 0 ? "exception " + std::to_string(rc) : modbus_strerror(last_errno_)));
  }

  // Plain block reads on the module unit (or the unit set by use_unit()).
  std::optional<std::vector<std::uint16_t>> holding(int address, int count) {
    std::vector<std::uint16_t> w(static_cast<std::size_t>(count));
    if (modbus_read_registers(ctx_, address, count, w.data()) < 0) {
      last_errno_ = errno;
      return std::nullopt;
    }
    return w;
  }

  // Raw request (unit id + PDU) and its confirmation: the reply PDU with the
  // unit id first, as libmodbus returns it minus the framing; empty on error.
  std::vector<std::uint8_t> raw(const std::vector<std::uint8_t>& unit_and_pdu) {
    if (modbus_send_raw_request(ctx_, unit_and_pdu.data(), static_cast<int>(unit_and_pdu.size())) < 0) {
      last_errno_ = errno;
      return {};
    }
    std::uint8_t rsp[MODBUS_MAX_ADU_LENGTH];
    const int n = modbus_receive_confirmation(ctx_, rsp);
    if (n < 0) {
      last_errno_ = errno;
      return {};
    }
    const int header = modbus_get_header_length(ctx_);  // TCP: 7 (MBAP incl. unit), RTU: 1 (unit)
    // Keep the unit id, drop the rest of the header (and the RTU CRC).
    const bool rtu = header == 1;
    std::vector<std::uint8_t> out(rsp + header - 1, rsp + n - (rtu ? 2 : 0));
    return out;
  }

  int last_errno() const { return last_errno_; }
  int last_exception() const { return exception_of(last_errno_); }

 private:
  Client(modbus_t* ctx, int module_unit, int sim_unit) : ctx_(ctx), module_unit_(module_unit), sim_unit_(sim_unit) {
    set_timeout(1000ms);
    if (modbus_connect(ctx_) != 0) {
      const int e = errno;
      modbus_free(ctx_);
      ctx_ = nullptr;
      throw std::runtime_error(std::string("modbus_connect failed: ") + modbus_strerror(e));
    }
    modbus_set_slave(ctx_, module_unit_);
  }
  void select(const registers::Register& r) {
    const int unit = r.unit == registers::Unit::simulator ? sim_unit_ : module_unit_;
    if (unit < 0) throw std::runtime_error("this client has no simulator unit (RTU): " + std::string(r.name()));
    modbus_set_slave(ctx_, unit);
  }

  modbus_t* ctx_ = nullptr;
  int module_unit_ = 1;
  int sim_unit_ = 247;
  int last_errno_ = 0;
};

// Every module holding register, name -> raw: "nothing changed" checks.
inline std::vector<std::pair<std::string, std::int64_t>> holding_snapshot(Client& c) {
  std::vector<std::pair<std::string, std::int64_t>> out;
  for (const registers::Register& r : registers::registers_of(registers::Unit::module))
    if (r.table == registers::Table::holding_register) out.emplace_back(r.name(), c.read(r.name()));
  return out;
}

// ---------------------------------------------------------------- raw TCP
// One Modbus/TCP transaction on its own socket, framed here: for PDUs that
// libmodbus cannot frame or parse (FC 43/14). Returns the reply PDU (function
// code first), or empty when nothing came within the timeout.
inline std::vector<std::uint8_t> raw_tcp_transaction(int port, std::uint8_t unit, const std::vector<std::uint8_t>& pdu,
                                                     std::chrono::milliseconds timeout = 2000ms) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    ::close(fd);
    return {};
  }
  std::vector<std::uint8_t> frame{0x12, 0x34, 0, 0, static_cast<std::uint8_t>((pdu.size() + 1) >> 8),
                                  static_cast<std::uint8_t>((pdu.size() + 1) & 0xFF), unit};
  frame.insert(frame.end(), pdu.begin(), pdu.end());
  (void)::send(fd, frame.data(), frame.size(), MSG_NOSIGNAL);
  std::vector<std::uint8_t> got;
  const auto deadline = Clock::now() + timeout;
  std::size_t want = 7;
  while (got.size() < want && Clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    std::uint8_t buf[300];
    const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
    if (n <= 0) break;
    got.insert(got.end(), buf, buf + n);
    if (got.size() >= 6) want = 6 + ((got[4] << 8) | got[5]);
  }
  ::close(fd);
  if (got.size() < want || got.size() < 8) return {};
  return std::vector<std::uint8_t>(got.begin() + 7, got.begin() + static_cast<long>(want));
}

// ---------------------------------------------------------------- waiting
// Polls pred every `every` until it holds or the timeout passes.
inline bool wait_until(const std::function<bool()>& pred, std::chrono::milliseconds timeout,
                       std::chrono::milliseconds every = 10ms) {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    if (pred()) return true;
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(every);
  }
}

// ---------------------------------------------------------------- pty pair
// socat -d -d pty,raw,echo=0 pty,raw,echo=0: two linked pseudo-terminals.
class PtyPair {
 public:
  PtyPair() {
    if (!program_exists("socat")) throw std::runtime_error("socat is not installed (tools/install-deps.sh)");
    log_ = dir_.file("socat.log");
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 2, log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    std::vector<std::string> argv{"socat", "-d", "-d", "pty,raw,echo=0", "pty,raw,echo=0"};
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    const int rc = ::posix_spawnp(&pid_, "socat", &fa, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) throw std::runtime_error(std::string("cannot start socat: ") + std::strerror(rc));
    // "... N PTY is /dev/pts/5" twice, then "starting data transfer loop".
    const bool ok = wait_until(
        [&] {
          ends_.clear();
          std::istringstream in(read_file(log_));
          std::string line;
          bool started = false;
          while (std::getline(in, line)) {
            if (auto at = line.find("PTY is "); at != std::string::npos) ends_.push_back(line.substr(at + 7));
            if (line.find("starting data transfer loop") != std::string::npos) started = true;
          }
          return ends_.size() == 2 && started;
        },
        5s);
    if (!ok) {
      (void)end_process(pid_, SIGTERM, 2s);
      pid_ = -1;
      throw std::runtime_error("socat gave no pty pair: " + read_file(log_));
    }
  }
  ~PtyPair() {
    if (pid_ > 0) (void)end_process(pid_, SIGTERM, 3s);
  }
  PtyPair(const PtyPair&) = delete;
  PtyPair& operator=(const PtyPair&) = delete;
  const std::string& server_end() const { return ends_[0]; }
  const std::string& client_end() const { return ends_[1]; }

 private:
  TempDir dir_;
  std::string log_;
  pid_t pid_ = -1;
  std::vector<std::string> ends_;
};

}  // namespace e2e
