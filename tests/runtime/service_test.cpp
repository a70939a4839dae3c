// What a Modbus client sees when the disk fails or the settings were lost,
// checked on the real request path (ModbusService) with the loop stepped by hand.
#include <catch2/catch.hpp>

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <thread>

#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>
#include <toml++/toml.h>

#include "fault_vfs.hpp"
#include "homing/gpiod/config.hpp"
#include "homing/sim/simulator_io.hpp"
#include "persistence/event_outbox.hpp"
#include "persistence/settings_store.hpp"
#include "registers/defaults.hpp"
#include "registers/errors.hpp"
#include "registers/lookup.hpp"
#include "registers/sim_bindings.hpp"
#include "server/control_loop.hpp"
#include "server/modbus_service.hpp"
#include "server/monitor.hpp"
#include "server/plant_events.hpp"
#include "tests/support/captured_log.hpp"
#include "tests/support/temp_dir.hpp"

namespace {

// An FC 05 or 06 request: function code, address, value.
using test_support::CapturedLog;

std::vector<std::uint8_t> single_write_pdu(std::uint8_t fc, std::uint16_t a, std::uint16_t v) {
  return {fc, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(v >> 8),
          static_cast<std::uint8_t>(v)};
}

struct Module {
  test_support::TempDir dir{"runtime-test"};  // removed after the members below are gone
  std::unique_ptr<persistence::SettingsStore> store;
  std::unique_ptr<server::ControlLoop> loop;
  std::unique_ptr<server::ModbusService> service;
  server::ClientInfo client{7, server::Transport::tcp, "127.0.0.1:50000"};

  // damaged_database: the settings file is junk and has no backup, so the
  // module starts on defaults with settings lost.
  explicit Module(bool faulty_disk, server::ServiceConfig config = {}, bool damaged_database = false) {
    if (damaged_database) std::ofstream(dir.file("settings.db"), std::ios::binary) << std::string(8192, 'x');
    std::vector<persistence::SettingDefault> defaults;
    for (const auto& [name, value] : registers::persisted_defaults()) defaults.push_back({name, value});
    persistence::StoreOptions options;
    if (faulty_disk) {
      fault_vfs::install();
      options.vfs = fault_vfs::kName;
    }
    persistence::OpenReport report;
    auto opened = persistence::SettingsStore::open(dir.file("settings.db"), defaults, report, options);
    REQUIRE(opened);
    store = std::make_unique<persistence::SettingsStore>(std::move(*opened));
    const auto settings = registers::settings_from_raw(store->load()).settings;
    auto io = std::make_unique<homing::sim::SimulatorIo>(registers::default_sim_config());
    loop = std::make_unique<server::ControlLoop>(settings, std::move(io), 1000, 1.0);
    service = std::make_unique<server::ModbusService>(std::move(config), *loop, store.get(), settings);
  }
  ~Module() {
    service.reset();
    loop.reset();
    store.reset();
  }

  std::vector<std::uint8_t> request(std::vector<std::uint8_t> pdu) { return service->handle(1, pdu, client).pdu; }
  void periods(int n) {
    for (int i = 0; i < n; ++i) loop->run_period(0.001);
  }
  static std::uint16_t address(std::string_view name) { return registers::find_register(name)->address; }
  std::int64_t read_i32(std::string_view name) {
    const auto a = address(name);
    const auto r = request({3, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), 0, 2});
    REQUIRE(r.size() == 6);
    return static_cast<std::int32_t>((r[2] << 24) | (r[3] << 16) | (r[4] << 8) | r[5]);
  }
  std::vector<std::uint8_t> write_i32(std::string_view name, std::int32_t v) {
    const auto a = address(name);
    const auto u = static_cast<std::uint32_t>(v);
    return request({16, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), 0, 2, 4,
                    static_cast<std::uint8_t>(u >> 24), static_cast<std::uint8_t>(u >> 16),
                    static_cast<std::uint8_t>(u >> 8), static_cast<std::uint8_t>(u)});
  }
  std::vector<std::uint8_t> write_u16(std::string_view name, std::uint16_t v) {
    const auto a = address(name);
    return request({6, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(v >> 8),
                    static_cast<std::uint8_t>(v)});
  }
  // status.refusal_count, last_refused_register, last_refusal_reason, in one request.
  std::array<std::uint16_t, 3> last_refusal() {
    const auto a = address("status.refusal_count");
    const auto r = request({4, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), 0, 3});
    REQUIRE(r.size() == 8);
    return {static_cast<std::uint16_t>(r[2] << 8 | r[3]), static_cast<std::uint16_t>(r[4] << 8 | r[5]),
            static_cast<std::uint16_t>(r[6] << 8 | r[7])};
  }
  std::int64_t read_u16(std::string_view name) {
    const auto a = address(name);
    const auto r = request({3, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), 0, 1});
    REQUIRE(r.size() == 4);
    return (r[2] << 8) | r[3];
  }
  homing::Status status() const { return loop->snapshot().status; }
  // Steps the loop until pred holds (false after max_periods), calling each() every 10 periods.
  bool run_until(const std::function<bool()>& pred, int max_periods, const std::function<void()>& each = {}) {
    for (int i = 0; i < max_periods; ++i) {
      loop->run_period(0.001);
      if (each && i % 10 == 0) each();
      if (pred()) return true;
    }
    return false;
  }
  std::vector<std::uint8_t> coil(std::string_view name) {
    const auto a = address(name);
    return request({5, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), 0xFF, 0x00});
  }
};

}  // namespace

TEST_CASE("a settings write the disk cannot store is answered with exception 04 and changes nothing") {
  for (auto fault : {fault_vfs::Fault::disk_full, fault_vfs::Fault::read_only}) {
    Module m(true);
    REQUIRE(m.read_i32("axis.x.pull_off") == 1000);
    {
      fault_vfs::Scoped broken(fault);
      const auto reply = m.write_i32("axis.x.pull_off", 2500);
      REQUIRE(reply.size() == 2);
      CHECK(reply[0] == (16 | 0x80));
      CHECK(reply[1] == 4);
      CHECK(m.read_i32("axis.x.pull_off") == 1000);
      CHECK(m.service->settings().axes[0].pull_off_mm == 1.0);
      CHECK(m.store->value("axis.x.pull_off") == 1000);
      // Published as storage_failed, about the register written.
      const auto refusal = m.last_refusal();
      CHECK(refusal[0] == 1);
      CHECK(refusal[1] == Module::address("axis.x.pull_off"));
      CHECK(refusal[2] == static_cast<std::uint16_t>(registers::RefusalReason::storage_failed));
    }
    // The disk is back: the same write is stored and answered.
    const auto reply = m.write_i32("axis.x.pull_off", 2500);
    CHECK(reply.size() == 5);
    CHECK(m.read_i32("axis.x.pull_off") == 2500);
    CHECK(m.store->value("axis.x.pull_off") == 2500);
  }
}

TEST_CASE("settings lost at start block homing until the alarm is reset over Modbus") {
  Module m(false);
  m.loop->raise_settings_lost();
  m.periods(3);
  CHECK(m.loop->snapshot().status.global_alarm == homing::AlarmCode::settings_lost);
  CHECK(m.loop->snapshot().status.interlocks & homing::interlock::settings_lost);
  m.coil("cmd.home_all");
  m.periods(3);
  CHECK(m.loop->snapshot().status.last_command_result == homing::CommandResult::refused_alarm);
  CHECK_FALSE(m.loop->snapshot().status.homing);
  m.coil("cmd.reset_alarm");
  m.periods(3);
  CHECK(m.loop->snapshot().status.global_alarm == homing::AlarmCode::none);
  m.coil("cmd.home_all");
  m.periods(3);
  CHECK(m.loop->snapshot().status.homing);
}

TEST_CASE("a settings write that the GPIO wiring cannot run is refused with exception 03 and changes nothing") {
  // X, Y and Z have motors, A B C have no lines.
  auto wiring = homing::gpiod::parse_config(toml::parse(R"(
[gpiod]
chip = "gpiochip0"
[gpiod.axes.X]
steps_per_unit = 400
step = 1
dir = 2
home = 3
[gpiod.axes.Y]
steps_per_unit = 400
step = 4
dir = 5
home = 6
[gpiod.axes.Z]
steps_per_unit = 400
step = 8
dir = 9
home = 10
)"), "cabinet.toml");
  REQUIRE(wiring);
  server::ServiceConfig config;
  config.machine_check = [w = *wiring](const homing::Settings& s) { return homing::gpiod::check_wiring(w, s); };
  Module m(false, config);
  // A would move on its own output, which it does not have.
  auto reply = m.write_u16("axis.a.mode", 2);
  REQUIRE(reply.size() == 2);
  CHECK(reply[0] == (6 | 0x80));
  CHECK(reply[1] == 3);
  CHECK(m.store->value("axis.a.mode") == 0);
  CHECK(m.service->settings().axes[3].mode == homing::HomingMode::disabled);
  const auto refusal = m.last_refusal();
  CHECK(refusal[0] == 1);
  CHECK(refusal[1] == Module::address("axis.a.mode"));
  CHECK(refusal[2] == static_cast<std::uint16_t>(registers::RefusalReason::wiring));
  // Y is wired: its mode may change.
  CHECK(m.write_u16("axis.y.mode", 3).size() == 5);
  CHECK(m.store->value("axis.y.mode") == 3);
}

TEST_CASE("the write allow-list binds network clients only: a client on the serial line writes, one outside the list does not") {
  server::ServiceConfig config;
  config.write_allow.push_back(*server::parse_cidr("10.0.0.0/8"));
  Module m(false, config);
  const auto before = m.store->value("axis.y.mode");
  REQUIRE(before != 3);
  // The TCP client at 127.0.0.1 is outside 10.0.0.0/8.
  auto reply = m.write_u16("axis.y.mode", 3);
  REQUIRE(reply.size() == 2);
  CHECK(reply[0] == (6 | 0x80));
  CHECK(reply[1] == 1);
  CHECK(m.store->value("axis.y.mode") == before);
  m.client = server::ClientInfo{8, server::Transport::rtu, "unit 1"};
  CHECK(m.write_u16("axis.y.mode", 3).size() == 5);
  CHECK(m.store->value("axis.y.mode") == 3);
  // The audit log names the transport the write came by.
  const auto audit = m.store->recent_changes(1);
  REQUIRE(audit);
  REQUIRE(audit->size() == 1);
  CHECK(audit->front().transport == "rtu");
  CHECK(audit->front().client == "unit 1");
}

TEST_CASE("an RTU broadcast write is applied to the module and answered with nothing") {
  Module m(false);
  const server::ClientInfo broadcast{0, server::Transport::rtu, "broadcast"};
  const auto a = Module::address("axis.y.mode");
  const std::vector<std::uint8_t> write{6, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), 0, 3};
  REQUIRE(m.store->value("axis.y.mode") != 3);
  CHECK_FALSE(m.service->handle(0, write, broadcast).send);
  CHECK(m.store->value("axis.y.mode") == 3);
  // A refused broadcast is silent on the bus, but a PLC can read why.
  const std::vector<std::uint8_t> bad{6, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), 0, 99};
  CHECK_FALSE(m.service->handle(0, bad, broadcast).send);
  CHECK(m.store->value("axis.y.mode") == 3);
  const auto refusal = m.last_refusal();
  CHECK(refusal[0] == 1);
  CHECK(refusal[1] == a);
  CHECK(refusal[2] == static_cast<std::uint16_t>(registers::RefusalReason::out_of_range));
  // A read broadcast is not answered either; over TCP unit 0 is the module itself.
  const std::vector<std::uint8_t> read{3, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), 0, 1};
  CHECK_FALSE(m.service->handle(0, read, broadcast).send);
  CHECK(m.service->handle(0, read, m.client).pdu == std::vector<std::uint8_t>{3, 2, 0, 3});
}

TEST_CASE("a unit id that does not exist is exception 0B over TCP and silence over RTU") {
  Module m(false);
  const std::vector<std::uint8_t> read{3, 0, 0, 0, 1};
  CHECK(m.service->handle(9, read, m.client).pdu == std::vector<std::uint8_t>{0x83, 0x0B});
  const server::ClientInfo serial{0, server::Transport::rtu, "unit 1"};
  CHECK_FALSE(m.service->handle(9, read, serial).send);
  CHECK(m.service->handle(1, read, serial).send);
}

TEST_CASE("cmd.home_axes homes exactly the named axes in one cycle and reads back 0") {
  Module m(false);
  const auto reply = m.write_u16("cmd.home_axes", 0b011);  // X and Y
  REQUIRE(reply.size() == 5);  // echoed
  m.periods(3);
  REQUIRE(m.status().homing);
  CHECK(m.status().last_command_result == homing::CommandResult::accepted);
  CHECK(m.read_u16("cmd.home_axes") == 0);
  const double z0 = m.loop->snapshot().sim.axes[2].actual_position_mm;
  bool z_busy = false;
  REQUIRE(m.run_until([&] { return !m.status().homing; }, 200'000,
                      [&] { z_busy = z_busy || m.status().axes[2].busy; }));
  const homing::Status st = m.status();
  CHECK(st.homing_cycles == 1);
  CHECK(st.axes[0].homed);
  CHECK(st.axes[1].homed);
  CHECK_FALSE(st.axes[2].homed);
  CHECK_FALSE(z_busy);
  CHECK(m.loop->snapshot().sim.axes[2].actual_position_mm == z0);
}

TEST_CASE("a cmd.home_axes write the module refuses answers its exception and changes nothing") {
  Module m(false);
  const auto refused = [](const std::vector<std::uint8_t>& reply, std::uint8_t code) {
    return reply == std::vector<std::uint8_t>{6 | 0x80, code};
  };
  SECTION("no axis named, or a disabled one: 03") {
    const auto home_axes = Module::address("cmd.home_axes");
    CHECK(refused(m.write_u16("cmd.home_axes", 0), 3));
    CHECK(m.last_refusal() == std::array<std::uint16_t, 3>{1, home_axes,
                                                           static_cast<std::uint16_t>(registers::RefusalReason::no_axis_named)});
    CHECK(refused(m.write_u16("cmd.home_axes", 0b1000), 3));  // A is disabled by default
    CHECK(m.last_refusal() == std::array<std::uint16_t, 3>{2, home_axes,
                                                           static_cast<std::uint16_t>(registers::RefusalReason::axis_disabled)});
    m.periods(3);
    CHECK(m.status().command_count == 0);
    CHECK_FALSE(m.status().homing);
  }
  SECTION("while a cycle runs: 06, and the cycle goes on as it was") {
    REQUIRE(m.write_u16("cmd.home_axes", 0b001).size() == 5);
    m.periods(3);
    REQUIRE(m.status().homing);
    const auto count = m.status().command_count;
    CHECK(refused(m.write_u16("cmd.home_axes", 0b110), 6));
    CHECK(m.last_refusal()[2] == static_cast<std::uint16_t>(registers::RefusalReason::busy));
    m.periods(3);
    CHECK(m.status().command_count == count);
    CHECK(m.status().homing);
    CHECK_FALSE(m.status().axes[1].busy);
    CHECK_FALSE(m.status().axes[2].busy);
  }
  SECTION("while an alarm is latched: 04") {
    m.loop->raise_settings_lost();
    m.periods(3);
    REQUIRE(m.status().alarm);
    CHECK(refused(m.write_u16("cmd.home_axes", 0b001), 4));
    CHECK(m.last_refusal()[2] == static_cast<std::uint16_t>(registers::RefusalReason::homing_blocked));
    m.periods(3);
    CHECK(m.status().command_count == 0);
    CHECK_FALSE(m.status().homing);
  }
}

TEST_CASE("the home-correction statistics count only cycles that started homed: the first after start-up is "
          "recorded as excluded") {
  Module m(false);
  server::Monitor monitor(*m.loop, *m.service, m.store.get());
  std::int64_t now_ms = 0;
  const auto watch = [&] { monitor.poll(now_ms += 10); };
  watch();
  for (int cycle = 0; cycle < 2; ++cycle) {
    m.coil("cmd.home_all");
    REQUIRE(m.run_until([&] { return m.status().homing; }, 100, watch));
    REQUIRE(m.run_until([&] { return !m.status().homing; }, 400'000, watch));
    watch();
    REQUIRE(m.status().state == homing::MachineState::homed);
  }
  const auto runs = m.store->recent_runs(10);
  REQUIRE(runs);
  REQUIRE(runs->size() == 2);
  for (std::size_t a : {0u, 1u, 2u}) {
    INFO("axis " << a);
    const auto& first = (*runs)[1].axis[a];
    REQUIRE(first.present);
    CHECK(first.excluded == persistence::Excluded::not_homed_before);
    CHECK_FALSE(first.correction_mm);
    const auto& second = (*runs)[0].axis[a];
    REQUIRE(second.present);
    CHECK(second.excluded == persistence::Excluded::no);
    REQUIRE(second.correction_mm);
    CHECK(std::abs(*second.correction_mm) < 0.05);
    const auto summary = m.store->correction_summary(a, 10);
    REQUIRE(summary);
    CHECK(summary->count == 1);
  }
  // The registers show the statistics of the trusted cycle only.
  const auto mean = Module::address("axis.x.correction_mean");
  const auto r = m.request({4, static_cast<std::uint8_t>(mean >> 8), static_cast<std::uint8_t>(mean), 0, 2});
  REQUIRE(r.size() == 6);
  CHECK(std::abs(static_cast<std::int32_t>((r[2] << 24) | (r[3] << 16) | (r[4] << 8) | r[5])) < 50);  // µm
}

TEST_CASE("the plant's events stay in the order they happened when a setting is changed before the monitor saw "
          "the cycle that ended first") {
  Module m(false);
  auto outbox = persistence::EventOutbox::open(m.dir.file("settings.db.mqtt-events"), 100);
  REQUIRE(outbox);
  server::PlantEvents events(*outbox, m.store.get());
  server::Monitor monitor(*m.loop, *m.service, m.store.get());
  monitor.set_plant_events(&events);
  std::int64_t now_ms = 0;
  const auto watch = [&] { monitor.poll(now_ms += 10); };
  watch();
  m.coil("cmd.home_all");
  REQUIRE(m.run_until([&] { return m.status().homing; }, 100, watch));
  // The cycle ends while the monitor does not look (its thread late on a busy
  // machine), and a setting is changed before it looks again, with its
  // half-second housekeeping (which reads settings changes) due.
  REQUIRE(m.run_until([&] { return !m.status().homing; }, 400'000));
  REQUIRE(m.write_u16("axis.x.seek_feedrate", 1007).at(0) == 6);
  monitor.poll(now_ms += 1000);
  const auto kept = outbox->oldest(100);
  REQUIRE(kept);
  std::vector<persistence::EventKind> kinds;
  for (const auto& e : *kept) kinds.push_back(e.kind);
  using K = persistence::EventKind;
  CHECK(kinds == std::vector<K>{K::cycle_started, K::cycle_ended, K::setting_changed});
  for (std::size_t i = 1; i < kept->size(); ++i) CHECK((*kept)[i - 1].time_ms <= (*kept)[i].time_ms);
}

TEST_CASE("a write refused for its form (quantity, byte count, coil value) is counted, published and logged like any "
          "refused write") {
  Module m(false);
  CapturedLog log;
  using registers::RefusalReason;
  const auto seek = Module::address("axis.x.seek_feedrate");
  const auto hi = static_cast<std::uint8_t>(seek >> 8);
  const auto lo = static_cast<std::uint8_t>(seek);
  std::vector<std::uint8_t> too_many{16, hi, lo, 0, 124, 248};
  too_many.resize(6 + 248, 0);
  const auto reset = Module::address("cmd.reset_alarm");
  struct Case {
    const char* what;
    std::vector<std::uint8_t> pdu;
    RefusalReason reason;
    std::uint16_t address;
  };
  const std::vector<Case> cases{
      {"FC16 of 124 registers", too_many, RefusalReason::malformed_write, seek},
      {"FC16 byte count not twice the quantity", {16, hi, lo, 0, 1, 3, 0, 0, 0}, RefusalReason::malformed_write, seek},
      {"FC16 of 0 registers", {16, hi, lo, 0, 0, 0}, RefusalReason::empty, seek},
      {"FC5 with 1234", {5, static_cast<std::uint8_t>(reset >> 8), static_cast<std::uint8_t>(reset), 0x12, 0x34},
       RefusalReason::malformed_write, reset},
      {"FC15 of 1969 coils", {15, 0, 0, 0x07, 0xB1, 247}, RefusalReason::malformed_write, 0},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    INFO(cases[i].what);
    CHECK(m.request(cases[i].pdu) == std::vector<std::uint8_t>{static_cast<std::uint8_t>(cases[i].pdu[0] | 0x80), 3});
    CHECK(m.last_refusal() == std::array<std::uint16_t, 3>{static_cast<std::uint16_t>(i + 1), cases[i].address,
                                                           static_cast<std::uint16_t>(cases[i].reason)});
  }
  CHECK(m.read_u16("axis.x.seek_feedrate") == registers::find_register("axis.x.seek_feedrate")->default_raw);
  m.service->flush_refusal_log();
  CHECK_THAT(log.text(), Catch::Contains("malformed_write") && Catch::Contains("quantity 124"));
}

TEST_CASE("an RTU broadcast applies settings at once and cannot begin an edit session") {
  Module m(false);
  server::ClientInfo broadcast{0, server::Transport::rtu, "broadcast"};
  broadcast.broadcast = true;
  const auto pdu = single_write_pdu;
  // Begin: refused (and, as every broadcast, not answered).
  CHECK(m.service->handle(0, pdu(6, Module::address("edit.command"), 1), broadcast).send == false);
  CHECK(m.last_refusal()[2] == static_cast<std::uint16_t>(registers::RefusalReason::edit_broadcast));
  // A settings write applies at once: no session holds it back.
  CHECK(m.service->handle(0, pdu(6, Module::address("axis.x.seek_feedrate"), 1234), broadcast).send == false);
  CHECK(m.read_u16("axis.x.seek_feedrate") == 1234);
}

TEST_CASE("a jog coil reads back 0 once its client's disconnect released the jog") {
  Module m(false);
  const auto coil = Module::address("cmd.jog_plus.y");
  const std::vector<std::uint8_t> read{1, static_cast<std::uint8_t>(coil >> 8), static_cast<std::uint8_t>(coil), 0, 1};
  REQUIRE(m.coil("cmd.jog_plus.y").size() == 5);
  CHECK(m.request(read) == std::vector<std::uint8_t>{1, 1, 1});
  // Another client's disconnect leaves it held.
  m.service->disconnected(server::ClientInfo{8, server::Transport::tcp, "127.0.0.1:50001"});
  CHECK(m.request(read) == std::vector<std::uint8_t>{1, 1, 1});
  m.service->disconnected(m.client);
  CHECK(m.request(read) == std::vector<std::uint8_t>{1, 1, 0});
}

namespace {

// A module with its monitor, looked at by hand: watch() is one 10 ms look.
struct Watched {
  Module m{false};
  CapturedLog log;
  server::Monitor monitor{*m.loop, *m.service, m.store.get()};
  std::int64_t now_ms = 0;
  Watched() { watch(); }
  void watch() { monitor.poll(now_ms += 10); }
};

// Aborts the running cycle and steps the loop, without the monitor looking,
// until the axes have come to rest with the alarm latched.
void abort_unwatched(Module& m) {
  m.coil("cmd.abort");
  REQUIRE(m.run_until([&] { return !m.status().homing; }, 100));
  REQUIRE(m.status().alarm);
  REQUIRE(m.run_until([&] { return m.status().axes[2].velocity_mm_per_s == 0; }, 10'000));
}

}  // namespace

TEST_CASE("a cycle that ended in an alarm reset before the monitor looked is recorded and logged with that alarm") {
  Watched w;
  Module& m = w.m;
  const auto watch = [&] { w.watch(); };
  m.coil("cmd.home_all");
  REQUIRE(m.run_until([&] { return m.status().homing; }, 100, watch));
  watch();
  // Aborted, and reset at once (a PLC with an auto-reset), while the monitor does not look.
  abort_unwatched(m);
  m.coil("cmd.reset_alarm");
  REQUIRE(m.run_until([&] { return !m.status().alarm; }, 100));
  watch();
  const auto runs = m.store->recent_runs(10);
  REQUIRE(runs);
  REQUIRE(runs->size() == 1);
  CHECK(runs->front().result == static_cast<int>(homing::AlarmCode::aborted));
  const std::string text = w.log.text();
  CHECK_THAT(text, Catch::Contains("alarm 10 (aborted)"));
  CHECK_THAT(text, Catch::Contains("homing ended with alarm aborted"));
  CHECK_THAT(text, !Catch::Contains("homing done in"));
}

TEST_CASE("a cmd.home_axes written just after the heartbeat came back is not refused for the watchdog on a snapshot "
          "older than the heartbeat") {
  Module m(false);
  REQUIRE(m.write_u16("global.watchdog_ms", 100).at(0) == 6);
  m.periods(2);
  std::this_thread::sleep_for(std::chrono::milliseconds(150));  // the watchdog expires, nothing moving
  m.periods(1);
  REQUIRE((m.status().interlocks & homing::interlock::communication_lost) != 0);
  // The PLC beats again and, a scan later, starts X: no period between the two.
  REQUIRE(m.write_u16("host.heartbeat", 1).at(0) == 6);
  REQUIRE((m.status().interlocks & homing::interlock::communication_lost) != 0);
  CHECK(m.write_u16("cmd.home_axes", 0b001).at(0) == 6);
  m.periods(3);
  CHECK(m.status().homing);
  CHECK(m.status().last_command_result == homing::CommandResult::accepted);
}

TEST_CASE("every command judged is a command result line: two accepted in a row are two lines and several between "
          "two looks are one line with their count") {
  Watched w;
  Module& m = w.m;
  const auto count = [&](const std::string& what) {
    std::size_t n = 0;
    for (const std::string& line : w.log.sink->last_formatted()) n += line.find(what) != std::string::npos;
    return n;
  };
  const auto jog = [&](std::uint8_t on) {
    const auto a = Module::address("cmd.jog_plus.x");
    REQUIRE(m.request({5, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a), on, 0}).size() == 5);
    m.periods(3);
  };
  jog(0xFF);  // a jog: accepted
  w.watch();
  jog(0);
  m.run_until([&] { return m.status().state != homing::MachineState::moving; }, 5000);
  w.watch();
  CHECK(count("command result: accepted") == 1);
  jog(0xFF);  // accepted again: the same result, a new command
  w.watch();
  CHECK(count("command result: accepted") == 2);
  jog(0);
  m.run_until([&] { return m.status().state != homing::MachineState::moving; }, 5000);
  // Two presses before the monitor looks.
  jog(0xFF);
  jog(0);
  m.run_until([&] { return m.status().state != homing::MachineState::moving; }, 5000);
  jog(0xFF);
  w.watch();
  CHECK(count("command result: accepted (the last of 2 commands)") == 1);
  jog(0);
}

TEST_CASE("a cycle that started and ended between two looks of the monitor is recorded and logged") {
  Watched w;
  Module& m = w.m;
  const auto watch = [&] { w.watch(); };
  // Started and aborted while the monitor does not look (a short cycle, the
  // monitor's thread late on a busy machine).
  m.coil("cmd.home_all");
  REQUIRE(m.run_until([&] { return m.status().homing; }, 100));
  m.periods(20);
  abort_unwatched(m);
  watch();
  watch();
  const auto runs = m.store->recent_runs(10);
  REQUIRE(runs);
  REQUIRE(runs->size() == 1);
  CHECK(runs->front().result == static_cast<int>(homing::AlarmCode::aborted));
  CHECK(runs->front().axes != 0);
  const std::string text = w.log.text();
  CHECK_THAT(text, Catch::Contains("homing started"));
  CHECK_THAT(text, Catch::Contains("homing ended with alarm aborted"));
}

TEST_CASE("the history records an axis's correction only when its cycle succeeded and it started homed") {
  homing::AxisStatus axis;
  axis.home_correction_mm = 84.2;
  axis.homed_at_cycle_start = false;
  auto r = server::axis_record(true, axis, 1500);
  CHECK(r.present);
  CHECK(r.duration_ms == 1500);
  CHECK_FALSE(r.correction_mm);
  CHECK(r.excluded == persistence::Excluded::not_homed_before);
  axis.homed_at_cycle_start = true;
  axis.home_correction_mm = 0.003;
  r = server::axis_record(true, axis, 1500);
  REQUIRE(r.correction_mm);
  CHECK(*r.correction_mm == 0.003);
  CHECK(r.excluded == persistence::Excluded::no);
  r = server::axis_record(false, axis, 1500);
  CHECK_FALSE(r.correction_mm);
  CHECK(r.excluded == persistence::Excluded::cycle_failed);
}

TEST_CASE("a command or the heartbeat is answered at once on the caller's thread, a settings write or the simulator "
          "unit never is") {
  Module m(false);
  const auto pdu = single_write_pdu;
  const auto heartbeat = pdu(6, Module::address("host.heartbeat"), 42);
  const auto answered = m.service->handle_now(1, heartbeat, m.client);
  REQUIRE(answered);
  CHECK(answered->pdu == heartbeat);  // FC 06 echoed: applied
  CHECK(m.read_u16("host.heartbeat") == 42);
  const auto reset = pdu(5, Module::address("cmd.reset_alarm"), 0xFF00);
  CHECK(m.service->handle_now(1, reset, m.client).has_value());

  // Nothing done for these: the caller hands them to a thread that may wait.
  const auto seek = Module::address("axis.x.seek_feedrate");
  const auto seek_900 = pdu(6, seek, 900);
  const auto before = m.read_u16("axis.x.seek_feedrate");
  REQUIRE(before != 900);
  CHECK_FALSE(m.service->handle_now(1, seek_900, m.client).has_value());
  CHECK(m.read_u16("axis.x.seek_feedrate") == before);
  CHECK_FALSE(m.service->handle_now(1, pdu(6, Module::address("edit.command"), 1), m.client).has_value());
  const auto edit_state = Module::address("edit.state");
  CHECK(m.request({4, static_cast<std::uint8_t>(edit_state >> 8), static_cast<std::uint8_t>(edit_state), 0, 1}) ==
        std::vector<std::uint8_t>{4, 2, 0, 0});  // no session begun
  CHECK_FALSE(m.service->handle_now(247, pdu(6, 0, 0), m.client).has_value());
  const std::vector<std::uint8_t> read{3, 0, 0, 0, 1};
  CHECK_FALSE(m.service->handle_now(1, read, m.client).has_value());  // a read: not this path

  // A write refused before the write path (an address nobody has) releases what
  // handle_now held: the next settings write is still served.
  const auto nowhere = m.service->handle_now(1, pdu(6, 0xFFF0, 1), m.client);
  REQUIRE(nowhere);
  CHECK(nowhere->pdu.at(0) == (6 | 0x80));
  CHECK(m.write_u16("axis.x.seek_feedrate", 900) == seek_900);
  CHECK(m.read_u16("axis.x.seek_feedrate") == 900);
}

TEST_CASE("a reset that acknowledges lost settings is not answered on the caller's thread but by the settings writer "
          "once the acknowledgement is stored") {
  Module m(false, {}, true);
  REQUIRE(m.store->settings_lost());
  const auto reset = single_write_pdu(5, Module::address("cmd.reset_alarm"), 0xFF00);
  // An event loop asking handle_now gets nothing done: it hands the reset on.
  CHECK_FALSE(m.service->handle_now(1, reset, m.client).has_value());
  CHECK(m.store->settings_lost());
  std::promise<server::Reply> answered;
  auto reply = answered.get_future();
  REQUIRE(m.service->handle_later(1, reset, m.client, [&](server::Reply r) { answered.set_value(std::move(r)); }));
  REQUIRE(reply.wait_for(std::chrono::seconds(10)) == std::future_status::ready);
  CHECK(reply.get().pdu == reset);
  CHECK_FALSE(m.store->settings_lost());
  const auto audit = m.store->recent_changes(1);
  REQUIRE(audit);
  REQUIRE_FALSE(audit->empty());
  CHECK(audit->front().name == "settings_lost");
  // Acknowledged: the next reset is answered at once again.
  CHECK(m.service->handle_now(1, reset, m.client).has_value());
}

TEST_CASE("a reset refused for an e-stop still pressed leaves lost settings unacknowledged until a reset is taken") {
  Module m(false, {}, true);
  REQUIRE(m.store->settings_lost());
  m.loop->raise_settings_lost();
  REQUIRE(m.loop->edit_sim([](homing::sim::SimulatorControls& sim, const homing::Outputs&) { sim.set_estop(true); },
                           std::chrono::seconds(1)));
  m.periods(3);
  REQUIRE(m.status().interlocks & homing::interlock::estop);
  m.coil("cmd.reset_alarm");
  m.periods(3);
  CHECK(m.status().last_command_result == homing::CommandResult::refused_cause_present);
  // The flag stays: a restart now raises settings_lost again.
  CHECK(m.store->settings_lost());
  REQUIRE(m.loop->edit_sim([](homing::sim::SimulatorControls& sim, const homing::Outputs&) { sim.set_estop(false); },
                           std::chrono::seconds(1)));
  m.periods(3);
  m.coil("cmd.reset_alarm");
  m.periods(3);
  CHECK(m.status().last_command_result == homing::CommandResult::accepted);
  CHECK_FALSE(m.status().interlocks & homing::interlock::settings_lost);
  CHECK_FALSE(m.store->settings_lost());
}

namespace {

// Settings lost at start, the watchdog at 100 ms, the heartbeat written once
// and then not for 150 ms: expired, though no period has run since.
void expire_watchdog_with_settings_lost(Module& m) {
  REQUIRE(m.store->settings_lost());
  m.loop->raise_settings_lost();
  REQUIRE(m.write_u16("global.watchdog_ms", 100).at(0) == 6);
  m.write_u16("host.heartbeat", 1);
  m.periods(3);
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
}

}  // namespace

TEST_CASE("a reset written just after the heartbeat that ended a stale watchdog acknowledges lost settings as the "
          "engine takes it") {
  Module m(false, {}, true);
  expire_watchdog_with_settings_lost(m);
  m.periods(3);
  REQUIRE(m.status().interlocks & homing::interlock::communication_lost);
  // As homingctl does: the heartbeat, then the reset, before the loop ran a period.
  m.write_u16("host.heartbeat", 2);
  m.coil("cmd.reset_alarm");
  m.periods(3);
  CHECK(m.status().last_command_result == homing::CommandResult::accepted);
  CHECK_FALSE(m.status().interlocks & homing::interlock::settings_lost);
  CHECK_FALSE(m.store->settings_lost());
}

TEST_CASE("a PLC writing both jog coils of an axis in one FC 15 jogs the one written 1 and both held is no jog") {
  Module m(false);
  const auto plus = Module::address("cmd.jog_plus.x");
  const auto minus = Module::address("cmd.jog_minus.x");
  REQUIRE(minus == plus + 1);
  const auto both = [&](bool p, bool n) {
    const auto bits = static_cast<std::uint8_t>((p ? 1 : 0) | (n ? 2 : 0));
    REQUIRE(m.request({15, static_cast<std::uint8_t>(plus >> 8), static_cast<std::uint8_t>(plus), 0, 2, 1, bits})
                .size() == 5);
    m.periods(3);
  };
  const auto one = [&](std::uint16_t coil, bool on) {
    REQUIRE(m.request({5, static_cast<std::uint8_t>(coil >> 8), static_cast<std::uint8_t>(coil),
                       static_cast<std::uint8_t>(on ? 0xFF : 0), 0})
                .size() == 5);
    m.periods(3);
  };
  const auto read_both = [&] {
    return m.request({1, static_cast<std::uint8_t>(plus >> 8), static_cast<std::uint8_t>(plus), 0, 2});
  };
  const auto stops = [&] {
    return m.run_until([&] { return m.status().state != homing::MachineState::moving; }, 5000);
  };
  both(true, false);
  CHECK(m.status().state == homing::MachineState::moving);
  CHECK(m.status().axes[0].velocity_mm_per_s > 0);
  CHECK(read_both() == std::vector<std::uint8_t>{1, 1, 0x01});
  // The minus button pressed too: both held is no jog, and the coils read back as written.
  one(minus, true);
  CHECK(stops());
  CHECK(read_both() == std::vector<std::uint8_t>{1, 1, 0x03});
  // Releasing plus leaves minus held, not pressed: nothing starts by itself.
  one(plus, false);
  m.periods(50);
  CHECK(m.status().state != homing::MachineState::moving);
  one(minus, false);
  one(minus, true);  // a press
  CHECK(m.run_until([&] { return m.status().axes[0].velocity_mm_per_s < 0; }, 2000));
  one(minus, false);
  CHECK(stops());
  // Both written 1 in one request: no jog.
  both(true, true);
  m.periods(50);
  CHECK(m.status().state != homing::MachineState::moving);
  CHECK(read_both() == std::vector<std::uint8_t>{1, 1, 0x03});
  both(false, false);
}

TEST_CASE("a jog stops at the release or disconnect of any client that holds it and a client that never held it "
          "neither stops it nor leaves a coil stuck") {
  Module m(false);
  const server::ClientInfo old_link = m.client;  // a PLC whose connection lingers half-open
  const server::ClientInfo new_link{8, server::Transport::tcp, "127.0.0.1:50001"};  // the same PLC, reconnected
  const server::ClientInfo panel{9, server::Transport::tcp, "127.0.0.1:50002"};
  const auto plus = Module::address("cmd.jog_plus.x");
  const auto write = [&](const server::ClientInfo& who, std::uint16_t coil, bool on) {
    REQUIRE(m.service->handle(1, single_write_pdu(5, coil, on ? 0xFF00 : 0), who).pdu.size() == 5);
    m.periods(3);
  };
  const auto both = [&](const server::ClientInfo& who, bool p, bool n) {
    const auto bits = static_cast<std::uint8_t>((p ? 1 : 0) | (n ? 2 : 0));
    const std::vector<std::uint8_t> pdu{15, static_cast<std::uint8_t>(plus >> 8), static_cast<std::uint8_t>(plus), 0, 2, 1, bits};
    REQUIRE(m.service->handle(1, pdu, who).pdu.size() == 5);
    m.periods(3);
  };
  const auto coils = [&] {
    return m.request({1, static_cast<std::uint8_t>(plus >> 8), static_cast<std::uint8_t>(plus), 0, 2}).at(2);
  };
  const auto at_rest = [&] {
    return m.run_until([&] { return m.status().axes[0].velocity_mm_per_s == 0; }, 5000);
  };
  const auto jogging = [&] {
    m.periods(50);
    return m.status().axes[0].velocity_mm_per_s > 0;
  };
  const std::uint16_t minus = plus + 1;
  // The reconnected PLC goes on writing its held word, then the operator lets go.
  write(old_link, plus, true);
  REQUIRE(jogging());
  write(new_link, plus, true);
  CHECK(jogging());
  write(new_link, plus, false);
  CHECK(at_rest());
  CHECK(coils() == 0);
  // A panel rewriting its word with 0 never held the button: it changes nothing.
  write(old_link, plus, true);
  REQUIRE(jogging());
  write(panel, plus, false);
  CHECK(jogging());
  CHECK(coils() == 0x01);
  // Its press of the other direction stops the axis; its cyclic 0 on plus does
  // not release minus, and nothing restarts without a new press.
  both(panel, false, true);
  CHECK(at_rest());
  CHECK(coils() == 0x03);
  both(panel, false, true);
  CHECK_FALSE(jogging());
  // It leaves: its button reads 0, the PLC's still 1, and nothing starts.
  m.service->disconnected(panel);
  m.periods(3);
  CHECK(coils() == 0x01);
  CHECK_FALSE(jogging());
  m.service->disconnected(old_link);
  m.periods(3);
  CHECK(coils() == 0);
  // Both pressed by a client that then leaves: no coil stays stuck at 1, and
  // the next press of either direction jogs.
  both(panel, true, true);
  m.service->disconnected(panel);
  m.periods(3);
  CHECK(coils() == 0);
  write(new_link, minus, true);
  CHECK(m.run_until([&] { return m.status().axes[0].velocity_mm_per_s < 0; }, 2000));
  write(new_link, minus, false);
  CHECK(at_rest());
}

TEST_CASE("both jog coils written 1 in one FC 15 never show the running loop the first alone") {
  Module m(false);
  m.loop->start();
  const auto plus = Module::address("cmd.jog_plus.x");
  const auto both = [&](std::uint8_t bits) {
    const std::vector<std::uint8_t> pdu{15, static_cast<std::uint8_t>(plus >> 8), static_cast<std::uint8_t>(plus), 0, 2, 1, bits};
    REQUIRE(m.service->handle(1, pdu, m.client).pdu.size() == 5);
  };
  const std::uint32_t before = m.status().command_count;
  for (int i = 0; i < 200; ++i) {
    both(0x03);
    std::this_thread::sleep_for(std::chrono::microseconds(500));
    both(0x00);
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  // A jog taken for one period would have been judged, counted and started.
  CHECK(m.status().command_count == before);
  CHECK(m.status().axes[0].position_mm == 0);
  m.loop->stop();
}

TEST_CASE("a reset written after the watchdog expired but before a period showed it leaves lost settings "
          "unacknowledged") {
  Module m(false, {}, true);
  expire_watchdog_with_settings_lost(m);
  m.coil("cmd.reset_alarm");  // the last period still shows a fresh heartbeat
  m.periods(3);
  CHECK(m.status().last_command_result == homing::CommandResult::refused_cause_present);
  CHECK(m.store->settings_lost());
}

TEST_CASE("a jog coil written 1 again while it reads 1 is the button still held: a refused jog never restarts by itself") {
  Module m(false);
  const auto set_estop = [&](bool on) {
    REQUIRE(m.loop->edit_sim([on](homing::sim::SimulatorControls& sim, const homing::Outputs&) { sim.set_estop(on); },
                             std::chrono::seconds(1)));
    m.periods(3);
  };
  const auto jog = [&](bool on) {
    const auto a = Module::address("cmd.jog_plus.x");
    REQUIRE(m.request({5, static_cast<std::uint8_t>(a >> 8), static_cast<std::uint8_t>(a),
                       static_cast<std::uint8_t>(on ? 0xFF : 0), 0})
                .size() == 5);
    m.periods(3);
  };
  set_estop(true);
  const std::uint32_t before = m.status().command_count;
  jog(true);
  CHECK(m.status().command_count == before + 1);
  CHECK(m.status().last_command_result == homing::CommandResult::refused_estop);
  set_estop(false);
  m.coil("cmd.reset_alarm");
  m.periods(3);
  const std::uint32_t after_reset = m.status().command_count;
  jog(true);  // the coil reads 1 already: held, not pressed
  CHECK(m.status().command_count == after_reset);
  CHECK(m.status().state != homing::MachineState::moving);
  CHECK(m.status().axes[0].velocity_mm_per_s == 0);
  jog(false);
  jog(true);  // released and pressed: judged and taken
  CHECK(m.status().command_count == after_reset + 1);
  CHECK(m.status().last_command_result == homing::CommandResult::accepted);
  CHECK(m.status().state == homing::MachineState::moving);
  jog(false);
}

TEST_CASE("a simulator write on an event loop is answered by the running control loop once a published period shows "
          "it and made into its answer on the event loop's thread") {
  Module m(false);
  m.loop->start();
  struct Answer {
    std::mutex mutex;
    std::condition_variable came;
    std::optional<server::Reply> reply;
    std::thread::id on;
  };
  const auto later = [&m](const std::vector<std::uint8_t>& request, Answer& a) {
    return m.service->handle_later(247, request, m.client, [&a](server::Reply r) {
      std::lock_guard lock(a.mutex);
      a.reply = std::move(r);
      a.on = std::this_thread::get_id();
      a.came.notify_all();
    });
  };
  const auto wait = [](Answer& a) {
    std::unique_lock lock(a.mutex);
    return a.came.wait_for(lock, std::chrono::seconds(10), [&a] { return a.reply.has_value(); });
  };
  const auto press = single_write_pdu(5, Module::address("sim.estop"), 0xFF00);
  REQUIRE_FALSE(m.status().interlocks & homing::interlock::estop);
  Answer pressed;
  REQUIRE(later(press, pressed));
  REQUIRE(wait(pressed));
  CHECK(pressed.on != std::this_thread::get_id());  // the control loop's thread
  // Handed over undecided: the event loop makes the answer (and any log line).
  REQUIRE(pressed.reply->resolve);
  CHECK(pressed.reply->pdu.empty());
  const server::Reply answer = pressed.reply->resolve();
  CHECK(answer.pdu == press);
  // Answered once a published period shows it: the engine's status already has it.
  CHECK(m.status().interlocks & homing::interlock::estop);

  // Refused for its address at once, on the caller's thread, with nothing handed to the loop.
  Answer nowhere;
  REQUIRE(later(single_write_pdu(6, 0xFFF0, 1), nowhere));
  REQUIRE(wait(nowhere));
  CHECK(nowhere.on == std::this_thread::get_id());
  CHECK_FALSE(nowhere.reply->resolve);
  CHECK(nowhere.reply->pdu == std::vector<std::uint8_t>{6 | 0x80, 2});
  m.loop->stop();
}

TEST_CASE("a write of the module unit over TCP is taken by the settings writer and answered through its callback once "
          "stored, a refusal too, while reads, FC 23 and RTU are not taken") {
  Module m(false);
  const auto pdu = single_write_pdu;
  struct Answer {
    std::mutex mutex;
    std::condition_variable came;
    std::optional<server::Reply> reply;
    std::thread::id on;
    int calls = 0;
  };
  const auto later = [&m](std::uint8_t unit, const std::vector<std::uint8_t>& request, const server::ClientInfo& who,
                          Answer& a) {
    return m.service->handle_later(unit, request, who, [&a](server::Reply r) {
      std::lock_guard lock(a.mutex);
      a.reply = std::move(r);
      a.on = std::this_thread::get_id();
      ++a.calls;
      a.came.notify_all();
    });
  };
  const auto wait = [](Answer& a) {
    std::unique_lock lock(a.mutex);
    return a.came.wait_for(lock, std::chrono::seconds(10), [&a] { return a.reply.has_value(); });
  };

  const auto seek = Module::address("axis.x.seek_feedrate");
  const auto seek_900 = pdu(6, seek, 900);
  REQUIRE(m.read_u16("axis.x.seek_feedrate") != 900);
  Answer accepted;
  REQUIRE(later(1, seek_900, m.client, accepted));
  REQUIRE(wait(accepted));
  CHECK(accepted.reply->pdu == seek_900);  // FC 06 echoed: accepted
  CHECK(accepted.on != std::this_thread::get_id());
  CHECK(m.store->load().at("axis.x.seek_feedrate") == 900);  // on disk before the answer
  CHECK(m.read_u16("axis.x.seek_feedrate") == 900);

  // Refused by the same rules as handle(): exception 03, the refusal
  // registers name the register written, nothing stored.
  Answer refused;
  REQUIRE(later(1, pdu(6, seek, 0), m.client, refused));
  REQUIRE(wait(refused));
  CHECK(refused.reply->pdu == std::vector<std::uint8_t>{6 | 0x80, 3});
  const auto written = Module::address("status.last_refused_write");
  CHECK(m.request({4, static_cast<std::uint8_t>(written >> 8), static_cast<std::uint8_t>(written), 0, 1}) ==
        std::vector<std::uint8_t>{4, 2, static_cast<std::uint8_t>(seek >> 8), static_cast<std::uint8_t>(seek)});
  CHECK(m.store->load().at("axis.x.seek_feedrate") == 900);

  // A command coil through unit 0xFF (the module addressed by IP): taken, echoed.
  Answer reset;
  const auto reset_coil = pdu(5, Module::address("cmd.reset_alarm"), 0xFF00);
  REQUIRE(later(0xFF, reset_coil, m.client, reset));
  REQUIRE(wait(reset));
  CHECK(reset.reply->pdu == reset_coil);

  // Not taken, nothing done, the callback never called: the caller runs
  // these where waiting is allowed.
  Answer none;
  CHECK_FALSE(later(1, {3, 0, 0, 0, 1}, m.client, none));  // a read
  const std::vector<std::uint8_t> fc23{23, 0, 0, 0, 1, static_cast<std::uint8_t>(seek >> 8),
                                       static_cast<std::uint8_t>(seek), 0, 1, 2, 0x03, 0xE8};
  CHECK_FALSE(later(1, fc23, m.client, none));
  server::ClientInfo rtu{8, server::Transport::rtu, "/dev/ttyS0"};
  CHECK_FALSE(later(1, pdu(6, seek, 1000), rtu, none));
  CHECK(m.read_u16("axis.x.seek_feedrate") == 900);
  for (Answer* a : {&accepted, &refused, &reset}) CHECK(a->calls == 1);
  CHECK(none.calls == 0);
}
