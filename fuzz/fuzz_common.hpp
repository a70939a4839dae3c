#pragma once
// Shared by the request fuzz targets: a ModbusService in front of a control
// loop that is NOT started (the target steps it by hand after each request)
// on the default simulator, no settings store; and the invariants every
// request must keep. A violated invariant aborts with a message (libFuzzer
// then saves the input as a crash).
#include <signal.h>
#include <unistd.h>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <filesystem>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "homing/sim/simulator_io.hpp"
#include "registers/codec.hpp"
#include "registers/defaults.hpp"
#include "registers/lookup.hpp"
#include "registers/sim_bindings.hpp"
#include "server/control_loop.hpp"
#include "server/modbus_service.hpp"
#include "server/pdu.hpp"
#include "server/request_decoder.hpp"

namespace fuzz {

[[noreturn]] inline void violated(const char* what, std::uint8_t unit, std::span<const std::uint8_t> pdu) {
  std::fprintf(stderr, "INVARIANT VIOLATED: %s\n  unit %u, PDU (%zu bytes):", what, unit, pdu.size());
  for (std::size_t i = 0; i < pdu.size() && i < 64; ++i) std::fprintf(stderr, " %02X", pdu[i]);
  std::fprintf(stderr, "\n");
  std::abort();
}

inline void quiet_logs() { spdlog::set_level(spdlog::level::off); }

// LLVMFuzzerInitialize of the request targets: logs off, and the services
// built before the first input (so that building them is not timed as one).
template <class Services>
int initialize(Services& (*services)()) {
  quiet_logs();
  (void)services();
  return 0;
}

// Where the targets that need files keep them: tmpfs (/dev/shm) when there is
// one, so that writing an input, and the database's fsyncs, cost no disk I/O.
inline const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = [] {
    std::error_code ec;
    const std::filesystem::path shm = "/dev/shm";
    if (std::filesystem::is_directory(shm, ec) && ::access(shm.c_str(), W_OK) == 0) return shm;
    return std::filesystem::temp_directory_path();
  }();
  return dir;
}

// Temporary files are named <prefix><pid>...; libFuzzer ends a timed run with
// _Exit (no atexit), so files of processes that no longer exist are removed
// here at start.
inline void remove_stale_temp_files(const std::string& prefix) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(scratch_dir(), ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
    if (pid > 0 && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) std::filesystem::remove_all(e.path(), ec);
  }
}

constexpr std::uint8_t kModuleUnit = 1;
constexpr std::uint8_t kSimUnit = 247;
constexpr std::uint16_t kUnlockCode = 0xBEEF;  // the locked harness's --unlock-code

inline bool is_write_fc(std::uint8_t fc) { return fc == 5 || fc == 6 || fc == 15 || fc == 16 || fc == 23; }
inline bool is_exception(const server::Reply& r) { return r.send && !r.pdu.empty() && (r.pdu[0] & 0x80); }
// A write the service accepted: its normal (non-exception) reply.
inline bool accepted_write(std::uint8_t fc, const server::Reply& r) {
  return is_write_fc(fc) && r.send && !r.pdu.empty() && !(r.pdu[0] & 0x80);
}
inline bool contains_code(std::span<const std::uint8_t> pdu, std::uint16_t code) {
  for (std::size_t i = 0; i + 1 < pdu.size(); ++i)
    if (pdu[i] == (code >> 8) && pdu[i + 1] == (code & 0xFF)) return true;
  return false;
}

// Whether a coil starts motion when 1 is written to it: home, jog, move and
// the simulator's start button (home all on a press). cmd.abort,
// cmd.reset_alarm, cmd.lock_settings, the permit and the e-stop start nothing.
inline bool starts_motion(const registers::Register& coil) {
  using registers::Key;
  switch (coil.key) {
    case Key::cmd_home_all:
    case Key::cmd_home:
    case Key::cmd_jog_plus:
    case Key::cmd_jog_minus:
    case Key::cmd_move:
    case Key::sim_start_button: return true;
    default: return false;
  }
}

// Whether an accepted write may start motion: a 1 written to a coil that
// starts motion (above) on the unit it went to, or a holding write that covers
// cmd.home_axes (one cycle homes the axes it names). The PDU as the service
// decodes it; every unit but the simulator's addresses the module (unit 0 is
// the RTU broadcast, and 0 and 0xFF address the module over TCP).
inline bool commands_motion(std::uint8_t unit, std::span<const std::uint8_t> pdu) {
  if (pdu.empty()) return false;
  const auto request = server::decode_request(pdu);
  if (!request) return false;
  const server::WriteRequest* w = std::get_if<server::WriteRequest>(&request->body);
  if (const auto* rw = std::get_if<server::ReadWriteRequest>(&request->body)) w = &rw->write;
  if (!w) return false;
  if (w->table == registers::Table::coil) {
    const auto target = unit == kSimUnit ? registers::Unit::simulator : registers::Unit::module;
    for (std::size_t i = 0; i < w->values.size(); ++i) {
      if (w->values[i] == 0) continue;
      const registers::Register* r =
          registers::find_register(target, registers::Table::coil, static_cast<std::uint16_t>(w->start + i));
      if (r && starts_motion(*r)) return true;
    }
    return false;
  }
  static const std::uint16_t home_axes = registers::find_register("cmd.home_axes")->address;
  return w->table == registers::Table::holding_register && w->start <= home_axes &&
         home_axes < std::size_t{w->start} + w->values.size();
}

// The default machine, built once: seeding the simulator's random sources
// costs more than a whole request.
inline const homing::sim::Simulator& default_machine() {
  static const homing::sim::Simulator sim(registers::default_sim_config());
  return sim;
}

// The control loop owns its backend; the harness keeps the simulator backend
// across inputs (rebuilt in the same storage: a new 50 KB simulator each input
// would cost page faults), so the loop gets this stand-in that forwards to it.
class ForwardingIo final : public homing::MachineIo {
 public:
  explicit ForwardingIo(homing::MachineIo& io) : io_(io) {}
  void advance(const homing::Outputs& outputs, double dt_s) override { io_.advance(outputs, dt_s); }
  homing::Inputs read() override { return io_.read(); }
  void apply(const homing::Outputs& outputs) override { io_.apply(outputs); }
  void shutdown() override { io_.shutdown(); }
  homing::sim::SimulatorControls* simulator_controls() override { return io_.simulator_controls(); }

 private:
  homing::MachineIo& io_;
};

// One service as homingd builds it (simulator backend), store = nullptr.
// Built once per fuzz process and reset() before every input, so that each
// input starts from the same state: a new service on a new machine at rest.
// The loop is rebuilt in the same storage (a fresh allocation of its trace
// buffers each input would cost more than the requests), and only when a
// request reached the service since the last rebuild: a harness no request
// reached is still as new. For such a harness finish() has nothing to do: what
// it would see then is the same for every input (the engine, the simulator and
// its seeded noise are deterministic), and it is checked once, at start.
struct Harness {
  // read_only: a TCP client outside --write-allow; viewer and operator: TLS
  // clients whose certificate names that role (server/client_role.hpp).
  enum class Access { open, read_only, locked, viewer, operator_role };

  explicit Harness(Access a, server::Transport transport = server::Transport::tcp) : access(a) {
    if (a == Access::viewer || a == Access::operator_role) transport = server::Transport::tls;
    client = server::ClientInfo{7, transport, transport == server::Transport::rtu ? "unit 1" : "127.0.0.1:40000"};
    if (a == Access::viewer) {
      client.access = server::Access::read_only;
      client.identity = "CN=fuzz (role viewer)";
    }
    if (a == Access::operator_role) {
      client.access = server::Access::commands;
      client.identity = "CN=fuzz (role operator)";
    }
    config.unit_id = kModuleUnit;
    config.sim_unit_id = kSimUnit;
    if (a == Access::read_only) config.write_allow.push_back(*server::parse_cidr("10.0.0.0/8"));
    if (a == Access::locked) config.unlock_code = kUnlockCode;
    rebuild();
    finish_now();  // the input that sends no request
    rebuild();
  }
  Harness(const Harness&) = delete;
  Harness& operator=(const Harness&) = delete;

  void reset() {
    if (!untouched) rebuild();
  }

  // The settings the service holds: what the settings database would hold
  // (every setting is filled from its register, and only from it).
  homing::Settings settings() const { return service->settings(); }

  bool moving() const {
    const server::Snapshot s = loop->snapshot();
    if (s.status.homing) return true;
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (s.status.axes[a].velocity_mm_per_s != 0 || s.sim.axes[a].moving) return true;
    return false;
  }
  void print_motion() const {
    const server::Snapshot s = loop->snapshot();
    std::fprintf(stderr, "  homing %d, state %d\n", s.status.homing, static_cast<int>(s.status.state));
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      std::fprintf(stderr, "  axis %zu: velocity %g mm/s, phase %d, sim moving %d, sim position %g\n", a,
                   s.status.axes[a].velocity_mm_per_s, static_cast<int>(s.status.axes[a].phase), s.sim.axes[a].moving,
                   s.sim.axes[a].actual_position_mm);
  }

  void step(int periods = 1) {
    for (int i = 0; i < periods; ++i) {
      loop->run_period(0.001);
      elapsed_ns += 1'000'000;
    }
  }

  // One request through ModbusService::handle, then one control period; aborts
  // when an invariant breaks. Returns the reply.
  server::Reply request(std::uint8_t unit, std::span<const std::uint8_t> pdu) {
    untouched = false;
    const auto before = std::move(settings_now);  // as the last request (or reset) left them
    const server::Reply reply = service->handle(unit, pdu, client);
    step();
    settings_now = settings();
    const std::uint8_t fc = pdu.empty() ? 0 : pdu[0];
    // The reply itself: a PDU that fits a frame, for the function asked.
    if (reply.send) {
      if (reply.pdu.empty() || reply.pdu.size() > server::kMaxPdu) violated("reply PDU empty or too long", unit, pdu);
      if ((reply.pdu[0] & 0x7F) != (fc & 0x7F)) violated("reply for another function code", unit, pdu);
      if ((reply.pdu[0] & 0x80) && reply.pdu.size() != 2) violated("exception reply is not 2 bytes", unit, pdu);
    }
    const bool accepted = accepted_write(fc, reply);
    if (access == Access::read_only && accepted) violated("a client outside --write-allow got a write accepted", unit, pdu);
    if (access == Access::viewer && accepted) violated("a TLS viewer got a write accepted", unit, pdu);
    if (access == Access::operator_role && accepted && unit == kSimUnit)
      violated("a TLS operator got a write to the simulator unit accepted", unit, pdu);
    if (access == Access::operator_role && settings_now != before) violated("a TLS operator changed a setting", unit, pdu);
    // Settings change only by an accepted write of holding registers to the module.
    if (settings_now != before) {
      // Over TCP, unit ids 0xFF and 0 address the module too.
      const bool module_unit =
          unit == kModuleUnit || (client.transport == server::Transport::tcp && (unit == 0 || unit == 0xFF));
      if (!(accepted && module_unit && (fc == 6 || fc == 16 || fc == 23)))
        violated("settings changed by a request that was not an accepted settings write", unit, pdu);
      if (access == Access::locked && !maybe_unlocked && !contains_code(pdu, kUnlockCode))
        violated("locked settings changed without the unlock code", unit, pdu);
    }
    if (access == Access::locked && accepted && contains_code(pdu, kUnlockCode)) maybe_unlocked = true;
    // Motion only after an accepted write that commands it.
    if (accepted && commands_motion(unit, pdu)) motion_allowed = true;
    if (!motion_allowed && moving()) {
      print_motion();
      violated("an axis moves but no write that commands motion was accepted", unit, pdu);
    }
    return reply;
  }

  // An RTU broadcast (unit 0) as the bus delivers it, then one control
  // period; returns the reply (the caller checks that there is none).
  server::Reply broadcast(std::span<const std::uint8_t> pdu) {
    untouched = false;
    const server::Reply reply = service->handle(0, pdu, client);
    step();
    settings_now = settings();
    return reply;
  }

  // The client goes away (TCP connection closed), a few periods pass.
  void finish() {
    if (!untouched) finish_now();
  }

  Access access;
  server::ClientInfo client;
  server::ServiceConfig config;
  std::optional<homing::sim::SimulatorIo> machine;  // the loop below drives it
  std::optional<server::ControlLoop> loop;
  std::optional<server::ModbusService> service;
  bool motion_allowed = false;
  bool maybe_unlocked = false;
  bool untouched = false;                  // no request since the last rebuild
  homing::Settings settings_now;  // settings() after the last request, broadcast or rebuild
  std::int64_t elapsed_ns = 0;    // the periods stepped since the last rebuild

 private:
  void rebuild() {
    service.reset();
    loop.reset();
    machine.emplace(default_machine());
    // The watchdog on this harness's periods, not the wall clock: services
    // compared with each other see it expire alike, and an input replays alike.
    elapsed_ns = 0;
    loop.emplace(defaults(), std::make_unique<ForwardingIo>(*machine), 1000, 1.0, [this] { return elapsed_ns; });
    service.emplace(config, *loop, nullptr, defaults());
    motion_allowed = false;
    maybe_unlocked = false;
    untouched = true;
    settings_now = defaults();
  }

  void finish_now() {
    service->disconnected(client);
    step(5);
    if (!motion_allowed && moving()) {
      print_motion();
      violated("an axis moves at the end but no write that commands motion was accepted", 0, {});
    }
  }

  static const homing::Settings& defaults() {
    static const homing::Settings s = registers::default_settings();
    return s;
  }
};

}  // namespace fuzz
