// The unlock code's guard against guessing, with a clock driven by hand: the
// policy alone (server/unlock_guard.hpp), then through ModbusService as a
// Modbus client meets it (FC 06 to security.unlock, FC 16 to the 32-bit
// security.unlock32, the lockout in status.unlock_lockout_s).
#include <catch2/catch.hpp>

#include <chrono>
#include <memory>

#include "homing/sim/simulator_io.hpp"
#include "registers/defaults.hpp"
#include "registers/errors.hpp"
#include "registers/lookup.hpp"
#include "registers/sim_bindings.hpp"
#include "server/control_loop.hpp"
#include "server/modbus_service.hpp"
#include "server/unlock_guard.hpp"

using namespace std::chrono_literals;
using server::UnlockGuard;
using server::UnlockPolicy;
using server::UnlockVerdict;
using Time = UnlockGuard::Clock::time_point;

namespace {

constexpr std::uint32_t kCode = 4321;

}  // namespace

TEST_CASE("five wrong unlock codes in a row lock every unlock out for 10 s, doubling with each further one up to the cap") {
  UnlockGuard guard(kCode, UnlockPolicy{5, 10s, 60s});
  Time t{};
  for (std::uint32_t n = 1; n <= 4; ++n) {
    const auto o = guard.attempt(n, t);
    CHECK(o.verdict == UnlockVerdict::wrong);
    CHECK_FALSE(o.lockout_started);
    CHECK(guard.remaining(t) == 0s);
  }
  auto o = guard.attempt(5, t);
  CHECK(o.verdict == UnlockVerdict::wrong);
  CHECK(o.lockout_started);
  CHECK(o.lockout == 10s);
  CHECK(o.wrong_in_a_row == 5);
  CHECK(guard.remaining(t) == 10s);
  CHECK(guard.remaining(t + 9500ms) == 1s);  // rounded up: still locked out
  // Each wrong code once a lockout has passed: 20 s, 40 s, then the cap.
  for (const auto expected : {20s, 40s, 60s, 60s}) {
    t += guard.remaining(t);
    o = guard.attempt(6, t);
    CHECK(o.verdict == UnlockVerdict::wrong);
    CHECK(o.lockout == expected);
    CHECK(guard.remaining(t) == expected);
  }
  CHECK(guard.wrong_in_a_row() == 9);
}

TEST_CASE("during a lockout the right code is refused too and a wrong code is neither compared nor counted") {
  UnlockGuard guard(kCode, UnlockPolicy{5, 10s, 900s});
  Time t{};
  for (std::uint32_t n = 1; n <= 5; ++n) guard.attempt(n, t);
  REQUIRE(guard.remaining(t) == 10s);
  CHECK(guard.attempt(kCode, t + 1s).verdict == UnlockVerdict::locked_out);
  CHECK(guard.attempt(kCode, t + 9999ms).verdict == UnlockVerdict::locked_out);
  for (std::uint32_t n = 0; n < 1000; ++n) CHECK(guard.attempt(n, t + 5s).verdict == UnlockVerdict::locked_out);
  CHECK(guard.wrong_in_a_row() == 5);
  CHECK(guard.remaining(t + 5s) == 5s);  // not lengthened by codes it did not try
  // Once it has passed, the right code works and the count starts again.
  CHECK(guard.attempt(kCode, t + 10s).verdict == UnlockVerdict::right);
  CHECK(guard.wrong_in_a_row() == 0);
  CHECK(guard.remaining(t + 10s) == 0s);
}

TEST_CASE("a sweep of every 16-bit code with the clock standing still never finds the code") {
  UnlockGuard guard(40000, UnlockPolicy{});
  const Time t{};
  int right = 0, compared = 0;
  for (std::uint32_t n = 1; n <= 65535; ++n) {
    const auto o = guard.attempt(n, t);
    right += o.verdict == UnlockVerdict::right;
    compared += o.verdict != UnlockVerdict::locked_out;
  }
  CHECK(right == 0);
  CHECK(compared == 5);
  CHECK(guard.wrong_in_a_row() == 5);
}

TEST_CASE("a right code before the limit resets the count of wrong codes in a row") {
  UnlockGuard guard(kCode, UnlockPolicy{});
  const Time t{};
  for (int round = 0; round < 10; ++round) {
    for (std::uint32_t n = 1; n <= 4; ++n) CHECK(guard.attempt(n, t).verdict == UnlockVerdict::wrong);
    CHECK(guard.attempt(kCode, t).verdict == UnlockVerdict::right);
  }
  CHECK(guard.wrong_in_a_row() == 0);
  CHECK(guard.remaining(t) == 0s);
}

TEST_CASE("a 32-bit code is compared whole: its low or high word alone is wrong") {
  constexpr std::uint32_t code = 3'000'000'123u;
  UnlockGuard guard(code, UnlockPolicy{});
  const Time t{};
  CHECK(guard.attempt(code & 0xFFFF, t).verdict == UnlockVerdict::wrong);
  CHECK(guard.attempt(code >> 16, t).verdict == UnlockVerdict::wrong);
  CHECK(guard.attempt(code, t).verdict == UnlockVerdict::right);
}

TEST_CASE("without a configured code every unlock is wrong") {
  UnlockGuard guard(0, UnlockPolicy{});
  CHECK(guard.attempt(0, Time{}).verdict == UnlockVerdict::wrong);
  CHECK(guard.attempt(1, Time{}).verdict == UnlockVerdict::wrong);
}

namespace {

// ModbusService on a simulated machine, its clock a variable the test moves.
struct Service {
  Time now{};
  std::unique_ptr<server::ControlLoop> loop;
  std::unique_ptr<server::ModbusService> service;
  server::ClientInfo client{7, server::Transport::tcp, "127.0.0.1:50000"};

  explicit Service(std::uint32_t code, UnlockPolicy policy = {}) {
    const auto settings = registers::settings_from_raw({}).settings;  // every default
    loop = std::make_unique<server::ControlLoop>(
        settings, std::make_unique<homing::sim::SimulatorIo>(registers::default_sim_config()), 1000, 1.0);
    server::ServiceConfig config;
    config.unlock_code = code;
    config.unlock_policy = policy;
    config.clock = [this] { return now; };
    service = std::make_unique<server::ModbusService>(std::move(config), *loop, nullptr, settings);
  }
  ~Service() {
    service.reset();
    loop.reset();
  }
  static std::uint16_t address(std::string_view name) { return registers::find_register(name)->address; }
  std::vector<std::uint8_t> request(std::vector<std::uint8_t> pdu) { return service->handle(1, pdu, client).pdu; }
  // FC 06 to security.unlock: 0 accepted, else the exception code.
  int unlock16(std::uint16_t v) {
    const auto a = address("security.unlock");
    return outcome(request({6, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a),
                            static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v)}));
  }
  // FC 16 to security.unlock32, high word first (the default --word-order).
  int unlock32(std::uint32_t v) {
    const auto a = address("security.unlock32");
    return outcome(request({16, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), 0, 2, 4,
                            static_cast<std::uint8_t>(v >> 24), static_cast<std::uint8_t>(v >> 16),
                            static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v)}));
  }
  static int outcome(const std::vector<std::uint8_t>& reply) {
    REQUIRE(!reply.empty());
    return (reply[0] & 0x80) ? reply.at(1) : 0;
  }
  std::int64_t input(std::string_view name) {
    const auto a = address(name);
    const auto r = request({4, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), 0, 1});
    REQUIRE(r.size() == 4);
    return (r[2] << 8) | r[3];
  }
};

constexpr int kIllegalDataValue = 3;
constexpr int kBusy = 6;

}  // namespace

TEST_CASE("over Modbus the lockout shows in status.unlock_lockout_s and refuses even the right code with exception 06") {
  Service s(kCode, UnlockPolicy{5, 10s, 900s});
  CHECK(s.input("status.settings_locked") == 1);
  for (std::uint16_t n = 1; n <= 5; ++n) CHECK(s.unlock16(n) == kIllegalDataValue);
  CHECK(s.input("status.wrong_unlock_codes") == 5);
  CHECK(s.input("status.unlock_lockout_s") == 10);
  CHECK(s.input("status.last_refusal_reason") == static_cast<int>(registers::RefusalReason::wrong_unlock_code));
  s.now += 4s;
  CHECK(s.input("status.unlock_lockout_s") == 6);
  CHECK(s.unlock16(kCode) == kBusy);
  CHECK(s.input("status.last_refusal_reason") == static_cast<int>(registers::RefusalReason::unlock_locked_out));
  CHECK(s.input("status.last_refused_register") == Service::address("security.unlock"));
  CHECK(s.input("status.settings_locked") == 1);
  s.now += 6s;
  CHECK(s.input("status.unlock_lockout_s") == 0);
  CHECK(s.unlock16(kCode) == 0);
  CHECK(s.input("status.settings_locked") == 0);
  CHECK(s.input("status.wrong_unlock_codes") == 0);
}

TEST_CASE("a 32-bit unlock code is written to security.unlock32 in one FC 16 request, a 16-bit one by FC 06 or FC 16") {
  SECTION("32-bit") {
    constexpr std::uint32_t code = 3'000'000'123u;
    Service s(code);
    CHECK(s.unlock32(code & 0xFFFF) == kIllegalDataValue);
    CHECK(s.unlock16(static_cast<std::uint16_t>(code & 0xFFFF)) == kIllegalDataValue);
    CHECK(s.input("status.wrong_unlock_codes") == 2);
    CHECK(s.input("status.last_refused_register") == Service::address("security.unlock"));
    CHECK(s.unlock32(code) == 0);
    CHECK(s.input("status.settings_locked") == 0);
  }
  SECTION("16-bit") {
    Service s(kCode);
    CHECK(s.unlock32(kCode) == 0);
    CHECK(s.input("status.settings_locked") == 0);
    CHECK(s.unlock16(kCode) == 0);
  }
  SECTION("one word of security.unlock32 alone is refused as half a 32-bit value and is no attempt") {
    Service s(kCode);
    const auto a = Service::address("security.unlock32");
    const auto r = s.request({6, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), 0x10, 0xE1});
    REQUIRE(r.size() == 2);
    CHECK(r[1] == 2);
    CHECK(s.input("status.wrong_unlock_codes") == 0);
  }
}

TEST_CASE("thousands of unlock codes over Modbus with the clock standing still never unlock the settings") {
  Service s(kCode);
  int accepted = 0;
  for (std::uint32_t n = 1; n <= 5000; ++n) accepted += s.unlock16(static_cast<std::uint16_t>(n)) == 0;
  CHECK(accepted == 0);
  CHECK(s.input("status.settings_locked") == 1);
  CHECK(s.input("status.wrong_unlock_codes") == 5);
  // Once the lockout has passed the right code works.
  s.now += std::chrono::seconds(s.input("status.unlock_lockout_s"));
  CHECK(s.unlock16(kCode) == 0);
  CHECK(s.input("status.settings_locked") == 0);
}

TEST_CASE("without an unlock code security.unlock and cmd.lock_settings are refused as no_unlock_code and count no wrong code") {
  Service s(0);
  CHECK(s.input("status.settings_locked") == 0);
  for (std::uint16_t n = 1; n <= 7; ++n) CHECK(s.unlock16(n) == kIllegalDataValue);
  CHECK(s.input("status.wrong_unlock_codes") == 0);
  CHECK(s.input("status.unlock_lockout_s") == 0);
  CHECK(s.input("status.last_refusal_reason") == static_cast<int>(registers::RefusalReason::no_unlock_code));
  CHECK(s.input("status.last_refused_register") == Service::address("security.unlock"));
  const auto lock = Service::address("cmd.lock_settings");
  const auto r = s.request({5, static_cast<std::uint8_t>(lock >> 8), static_cast<std::uint8_t>(lock), 0xFF, 0x00});
  CHECK(Service::outcome(r) == kIllegalDataValue);
  CHECK(s.input("status.last_refused_register") == lock);
  CHECK(s.input("status.settings_locked") == 0);
  // The settings stay writable.
  const auto feed = Service::address("axis.x.seek_feedrate");
  const auto w = s.request({6, static_cast<std::uint8_t>(feed >> 8), static_cast<std::uint8_t>(feed), 0x03, 0xEF});
  CHECK(Service::outcome(w) == 0);
}
