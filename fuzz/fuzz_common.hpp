#pragma once
// Shared by the request fuzz targets: a ModbusService in front of a control
// loop that is NOT started (the target steps it by hand after each request)
// on the default simulator, no settings store; and the invariants every
// request must keep. A violated invariant aborts with a message (libFuzzer
// then saves the input as a crash).
#include <signal.h>
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

#include "registers/codec.hpp"
#include "registers/defaults.hpp"
#include "registers/sim_bindings.hpp"
#include "server/control_loop.hpp"
#include "server/modbus_service.hpp"
#include "server/pdu.hpp"
#include "server/simulator_io.hpp"

namespace fuzz {

[[noreturn]] inline void violated(const char* what, std::uint8_t unit, std::span<const std::uint8_t> pdu) {
  std::fprintf(stderr, "INVARIANT VIOLATED: %s\n  unit %u, PDU (%zu bytes):", what, unit, pdu.size());
  for (std::size_t i = 0; i < pdu.size() && i < 64; ++i) std::fprintf(stderr, " %02X", pdu[i]);
  std::fprintf(stderr, "\n");
  std::abort();
}

inline void quiet_logs() { spdlog::set_level(spdlog::level::off); }

// Temporary files are named <prefix><pid>...; libFuzzer ends a timed run with
// _Exit (no atexit), so files of processes that no longer exist are removed
// here at start.
inline void remove_stale_temp_files(const std::string& prefix) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(std::filesystem::temp_directory_path(), ec)) {
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

// server::SimulatorIo on the default machine, but copied from one built once:
// seeding the simulator's random sources costs more than a whole request.
class CopiedSimulatorIo final : public server::MachineIo {
 public:
  CopiedSimulatorIo() : sim_(prototype()) {}
  void advance(const homing::Outputs& outputs, double dt_s) override {
    if (dt_s > 0) sim_.advance(outputs, dt_s);
  }
  homing::Inputs read() override { return sim_.inputs(); }
  homing::sim::Simulator& sim() { return sim_; }

 private:
  static const homing::sim::Simulator& prototype() {
    static const homing::sim::Simulator sim(registers::default_sim_config());
    return sim;
  }
  homing::sim::Simulator sim_;
};

// One service as homingd builds it (simulator backend), store = nullptr.
// Built once per fuzz process and reset() before every input, so that each
// input starts from the same state: a new service on a new machine at rest.
// The loop is rebuilt in the same storage (a fresh allocation of its trace
// buffers each input would cost more than the requests).
struct Harness {
  enum class Access { open, read_only, locked };

  explicit Harness(Access a, server::Transport transport = server::Transport::tcp) : access(a) {
    client = server::ClientInfo{7, transport, transport == server::Transport::tcp ? "127.0.0.1:40000" : "unit 1"};
    config.unit_id = kModuleUnit;
    config.sim_unit_id = kSimUnit;
    if (a == Access::read_only) config.write_allow.push_back(*server::parse_cidr("10.0.0.0/8"));
    if (a == Access::locked) config.unlock_code = kUnlockCode;
    reset();
  }
  Harness(const Harness&) = delete;
  Harness& operator=(const Harness&) = delete;

  void reset() {
    service.reset();
    loop.reset();
    auto io = std::make_unique<CopiedSimulatorIo>();
    homing::sim::Simulator* sim = &io->sim();
    loop.emplace(defaults(), std::move(io), sim, 1000, 1.0);
    service.emplace(config, *loop, nullptr, defaults());
    motion_allowed = false;
    maybe_unlocked = false;
  }

  // Every persisted setting as its raw register value, in table order: what
  // the settings database would hold.
  std::vector<std::int64_t> settings() const {
    const homing::Settings s = service->settings();
    std::vector<std::int64_t> raw;
    raw.reserve(persisted().size());
    for (const registers::Register* r : persisted()) raw.push_back(registers::setting_raw(s, *r));
    return raw;
  }

  bool moving() const {
    const server::Snapshot s = loop->snapshot();
    if (s.status.homing) return true;
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      if (s.status.axes[a].velocity_mm_per_s != 0 || s.sim[a].moving) return true;
    return false;
  }
  void print_motion() const {
    const server::Snapshot s = loop->snapshot();
    std::fprintf(stderr, "  homing %d, state %d\n", s.status.homing, static_cast<int>(s.status.state));
    for (std::size_t a = 0; a < homing::kAxisCount; ++a)
      std::fprintf(stderr, "  axis %zu: velocity %g mm/s, phase %d, sim moving %d, sim position %g\n", a,
                   s.status.axes[a].velocity_mm_per_s, static_cast<int>(s.status.axes[a].phase), s.sim[a].moving,
                   s.sim[a].actual_position_mm);
  }

  void step(int periods = 1) {
    for (int i = 0; i < periods; ++i) loop->run_period(0.001);
  }

  // One request through ModbusService::handle, then one control period; aborts
  // when an invariant breaks. Returns the reply.
  server::Reply request(std::uint8_t unit, std::span<const std::uint8_t> pdu) {
    const auto before = settings();
    const server::Reply reply = service->handle(unit, pdu, client);
    step();
    const std::uint8_t fc = pdu.empty() ? 0 : pdu[0];
    // The reply itself: a PDU that fits a frame, for the function asked.
    if (reply.send) {
      if (reply.pdu.empty() || reply.pdu.size() > server::kMaxPdu) violated("reply PDU empty or too long", unit, pdu);
      if ((reply.pdu[0] & 0x7F) != (fc & 0x7F)) violated("reply for another function code", unit, pdu);
      if ((reply.pdu[0] & 0x80) && reply.pdu.size() != 2) violated("exception reply is not 2 bytes", unit, pdu);
    }
    const bool accepted = accepted_write(fc, reply);
    if (access == Access::read_only && accepted) violated("a client outside --write-allow got a write accepted", unit, pdu);
    // Settings change only by an accepted write of holding registers to the module.
    if (settings() != before) {
      // Over TCP, unit ids 0xFF and 0 address the module too.
      const bool module_unit =
          unit == kModuleUnit || (client.transport == server::Transport::tcp && (unit == 0 || unit == 0xFF));
      if (!(accepted && module_unit && (fc == 6 || fc == 16 || fc == 23)))
        violated("settings changed by a request that was not an accepted settings write", unit, pdu);
      if (access == Access::locked && !maybe_unlocked && !contains_code(pdu, kUnlockCode))
        violated("locked settings changed without the unlock code", unit, pdu);
    }
    if (access == Access::locked && accepted && contains_code(pdu, kUnlockCode)) maybe_unlocked = true;
    // Motion only after an accepted coil write (commands, the simulator's start button).
    if (accepted && (fc == 5 || fc == 15)) motion_allowed = true;
    if (!motion_allowed && moving()) {
      print_motion();
      violated("an axis moves but no coil write was accepted", unit, pdu);
    }
    return reply;
  }

  // The client goes away (TCP connection closed), a few periods pass.
  void finish() {
    service->disconnected(client);
    step(5);
    if (!motion_allowed && moving()) {
      print_motion();
      violated("an axis moves at the end but no coil write was accepted", 0, {});
    }
  }

  Access access;
  server::ClientInfo client;
  server::ServiceConfig config;
  std::optional<server::ControlLoop> loop;
  std::optional<server::ModbusService> service;
  bool motion_allowed = false;
  bool maybe_unlocked = false;

 private:
  static const homing::Settings& defaults() {
    static const homing::Settings s = registers::default_settings();
    return s;
  }
  static const std::vector<const registers::Register*>& persisted() {
    static const std::vector<const registers::Register*> regs = [] {
      std::vector<const registers::Register*> out;
      for (const registers::Register& r : registers::registers_of(registers::Unit::module))
        if (r.persisted) out.push_back(&r);
      return out;
    }();
    return regs;
  }
};

}  // namespace fuzz
