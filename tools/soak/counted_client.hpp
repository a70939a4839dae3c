#pragma once
// One soak client: the shared register-name Modbus client (tests/support)
// with every request timed and counted, and failed reads reported as
// violations (reads must always work).
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "results.hpp"
#include "tests/support/modbus_client.hpp"

namespace soak {

class CountedClient {
 public:
  CountedClient(const std::string& host, int port, int id, Shared& shared, int unit, int sim_unit);
  Stats stats;

  // Raw value, or nullopt (counted, and a violation).
  std::optional<std::int64_t> read(const std::string& name);
  // Block read of input registers on the module unit (status polls); nullopt is a violation.
  std::optional<std::vector<std::uint16_t>> read_inputs(int start, int count);
  // 0, the exception code, or -1 for no answer (counted by kind).
  int write(const std::string& name, std::int64_t raw);
  // A write that must be accepted (set-up and machine steps).
  bool must_write(const std::string& name, std::int64_t raw);
  // Counts an error kind that the caller decided was expected, not an error.
  void expected_exception();
  const std::string& last_error() const { return last_error_; }

 private:
  // Books one request that started at t0.
  void count(std::chrono::steady_clock::time_point t0, bool ok);

  test_support::Client client_;
  int id_;
  Shared& shared_;
  int unit_;
  int last_exception_ = 0;
  std::string last_error_;
};

}  // namespace soak
