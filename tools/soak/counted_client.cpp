#include "counted_client.hpp"

#include <fmt/format.h>

#include <cerrno>

namespace soak {

using Clock = std::chrono::steady_clock;

CountedClient::CountedClient(const std::string& host, int port, int id, Shared& shared, int unit, int sim_unit)
    : client_(test_support::Client::tcp(host, port, unit, sim_unit, std::chrono::seconds(2))),
      id_(id),
      shared_(shared),
      unit_(unit) {}

void CountedClient::count(Clock::time_point t0, bool ok) {
  stats.latency_ms.push_back(std::chrono::duration<float, std::milli>(Clock::now() - t0).count());
  ++stats.requests;
  last_exception_ = 0;
  if (ok) return;
  const int err = client_.last_errno();
  last_exception_ = test_support::exception_of(err);
  last_error_ = last_exception_ ? fmt::format("exception {:02X}", last_exception_)
                                : (err == ETIMEDOUT ? std::string("timeout") : std::string(modbus_strerror(err)));
  ++stats.errors[last_error_];
  if (!last_exception_) modbus_flush(client_.ctx());
}

std::optional<std::int64_t> CountedClient::read(const std::string& name) {
  const auto t0 = Clock::now();
  auto v = client_.try_read(name);
  count(t0, v.has_value());
  if (!v) shared_.violation(fmt::format("client {}: reading {} failed: {}", id_, name, last_error_));
  return v;
}

std::optional<std::vector<std::uint16_t>> CountedClient::read_inputs(int start, int count_of) {
  client_.use_unit(unit_);
  const auto t0 = Clock::now();
  auto words = client_.inputs(start, count_of);
  count(t0, words.has_value());
  if (!words)
    shared_.violation(fmt::format("client {}: reading input registers {}..{} failed: {}", id_, start,
                                  start + count_of - 1, last_error_));
  return words;
}

int CountedClient::write(const std::string& name, std::int64_t raw) {
  const auto t0 = Clock::now();
  const int rc = client_.write(name, raw);
  count(t0, rc == 0);
  return rc;
}

bool CountedClient::must_write(const std::string& name, std::int64_t raw) {
  const int rc = write(name, raw);
  if (rc != 0) shared_.violation(fmt::format("client {}: writing {} = {} failed: {}", id_, name, raw, last_error_));
  return rc == 0;
}

void CountedClient::expected_exception() {
  if (auto it = stats.errors.find(last_error_); it != stats.errors.end() && --it->second == 0) stats.errors.erase(it);
  ++stats.expected_busy;
}

}  // namespace soak
