#pragma once
// End-to-end tests of this build's homingd: the shared test support
// (tests/support: temporary directories, processes by PID, a homingd on a free
// loopback port, a register-name Modbus client, raw TCP transactions, pty
// pairs) with homingd's path filled in.
// The headers the tests relied on when all of this lived here.
#include <modbus/modbus.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <exception>
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

#include "tests/support/homingd.hpp"
#include "tests/support/modbus_client.hpp"
#include "tests/support/named_registers.hpp"
#include "tests/support/ports.hpp"
#include "tests/support/process.hpp"
#include "tests/support/pty_pair.hpp"
#include "tests/support/raw_tcp.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/wait.hpp"

#ifndef HOMINGD_PATH
#error "HOMINGD_PATH must be defined to the homingd executable"
#endif

namespace e2e {

using namespace test_support;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

inline std::string homingd_path() { return HOMINGD_PATH; }

// A homingd started for one test: this build's unless options.program names another.
// When the test is done with it, it is stopped with SIGTERM and must exit 0
// with no sanitizer report in its stderr, or the test fails: a leak or a
// use-after-free on disconnect or shutdown fails the sanitized build's run of
// the test that caused it. A test that means to kill it says so with
// stop(SIGKILL); the sanitizer reports still count then.
class Daemon : public Homingd {
 public:
  explicit Daemon(DaemonOptions options = {}) : Homingd(with_program(std::move(options))) {}
  // Not while an exception unwinds the test: it has failed already, and
  // Homingd's destructor still ends homingd with SIGTERM.
  ~Daemon() noexcept(false) {  // FAIL_CHECK throws once Catch2 aborts the run (-a, -x)
    if (std::uncaught_exceptions() > 0) return;
    if (const std::string problems = shutdown_problems(); !problems.empty()) FAIL_CHECK(problems);
  }
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

 private:
  static DaemonOptions with_program(DaemonOptions options) {
    if (options.program.empty()) options.program = homingd_path();
    return options;
  }
};

}  // namespace e2e
