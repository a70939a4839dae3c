#pragma once
// The policy that applies a decoded Modbus request (server/request_decoder.hpp):
// which unit ids exist, who may write (--write-allow), locked settings, the
// busy rule, the durable commit of a settings write, commands and the
// simulator unit. Transports (TCP, RTU) call handle() with a PDU; fuzzers can too.
// modbus_service.cpp routes, reads and writes the module's registers;
// modbus_service_commands.cpp hands commands to the loop; modbus_service_sim.cpp
// serves the simulator unit.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <optional>
#include <span>
#include <thread>

#include "jog_buttons.hpp"
#include "control_loop.hpp"
#include "device_identification.hpp"
#include "line_diagnostics.hpp"
#include "options.hpp"
#include "refusal_log.hpp"
#include "persistence/settings_store.hpp"
#include "registers/codec.hpp"
#include "registers/validate.hpp"
#include "request_decoder.hpp"
#include "request_handler.hpp"
#include "unlock_guard.hpp"
#include "edit_sessions.hpp"
#include "write_plan.hpp"

namespace server {

struct ServiceConfig {
  std::uint8_t unit_id = 1;
  std::optional<std::uint8_t> sim_unit_id = 247;  // absent with real hardware
  registers::WordOrder word_order = registers::WordOrder::high_first;
  std::vector<Cidr> write_allow;  // empty: every TCP client may write
  std::uint32_t unlock_code = 0;  // 0: settings are never locked
  UnlockPolicy unlock_policy;     // wrong codes in a row before the lockout, its length and cap
  std::chrono::seconds refusal_log_interval{10};  // refused writes: counts per client and reason per interval
  // The runtime's clock (the unlock lockout, the refusal log); empty: the
  // steady clock. Tests drive their own.
  std::function<std::chrono::steady_clock::time_point()> clock;
  // What the machine behind can do (GPIO wiring): settings it cannot run are
  // refused with exception 03 and the returned reason. Empty: anything.
  MachineCheck machine_check;
  DeviceIdentity identity;  // FC 43, FC 17
};

class ModbusService final : public RequestHandler {
 public:
  ModbusService(ServiceConfig config, ControlLoop& loop, persistence::SettingsStore* store,
                const homing::Settings& settings);
  ~ModbusService() override;  // writes the refusal counts not yet written
  ModbusService(const ModbusService&) = delete;
  ModbusService& operator=(const ModbusService&) = delete;

  Reply handle(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client) override;
  // Commands and host values (the heartbeat, move targets...) to the module
  // unit, while no batch of writes is being decided or committed: they have
  // nothing to make durable, so they are answered at once on the caller's
  // thread. Settings, edit sessions, the simulator unit, or a batch under
  // way: nullopt.
  std::optional<Reply> handle_now(std::uint8_t unit, std::span<const std::uint8_t> pdu,
                                  const ClientInfo& client) override;
  // Writes (FC 05, 06, 15, 16) to the module unit over TCP or TLS, taken by
  // the settings writer (modbus_service_writer.cpp): one thread that leads
  // every batch of them, so a settings write needs no thread of its own.
  // Writes (the same functions) to the simulator unit, handed to the control
  // loop, which answers them once a published period shows them
  // (modbus_service_sim.cpp). FC 23, RTU and reads: false.
  bool handle_later(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client,
                    std::function<void(Reply)> done) override;
  void disconnected(const ClientInfo& client) override;
  bool release_jogs(const ClientInfo& client) override;
  void bus_event(Transport transport, BusEvent event) override { diagnostics_.bus_event(transport, event); }
  LineCounters line_counters(Transport transport) const { return diagnostics_.counters(transport); }

  // Writes the refusal counts of an interval that has passed (the monitor
  // calls it now and then, so a flood's last counts are not kept back).
  void flush_refusal_log();
  // Ends the edit sessions left longer than global.edit_timeout_s (the
  // monitor calls it now and then, so the log says so when it happens).
  void flush_edit_sessions();

  // A command coil written from outside Modbus (the MQTT edge node's NCMD):
  // the very path of an FC 05 write by this client to the module unit, so the
  // same interlocks, roles and refusals. nullopt: accepted; else the refusal.
  std::optional<registers::Refusal> command(const registers::Register& coil, bool on, const ClientInfo& client);

  // Called by the monitor when an axis's positions_set count moved on: the
  // coordinate set by hand goes into the audit log (axis.<a>.position, old ->
  // new) with the client that asked for it last.
  void audit_position_set(std::size_t axis, double old_mm, double new_mm);

  // Called by the monitor with the history summary.
  void set_extras(const registers::StatusExtras& extras);
  homing::Settings settings() const;
  // Calls use with the module unit as a Modbus read would see it now (the MQTT
  // edge node reads its metrics through it: the same values, the same codec).
  void with_module_view(const std::function<void(const registers::ModuleView&)>& use);

 private:
  enum class Target { module, simulator };
  Reply route(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client);
  // The unit ids that address the module: its own, and over TCP or TLS 0xFF and 0.
  bool module_unit(std::uint8_t unit, bool network) const;
  Reply dispatch(Target target, std::span<const std::uint8_t> pdu, const ClientInfo& client);
  Reply apply(Target target, const Request& request, const ClientInfo& client);
  // The answer to an accepted FC 05, 06, 15 or 16: the echo or the quantity.
  static Reply accepted_write_reply(FunctionCode function, const WriteRequest& w);
  Reply read(Target target, std::uint8_t fc, const ReadRequest& request, const ClientInfo& client);
  registers::StatusExtras extras_now() const;  // under mutex_ (shared is enough)
  bool release_jogs_locked(const ClientInfo& client);  // under mutex_ (unique)
  // Validates and applies a write; nullopt when accepted.
  std::optional<Reply> write(Target target, std::uint8_t fc, const WriteRequest& request, const ClientInfo& client);
  std::optional<Reply> write_module(std::uint8_t fc, registers::Table table, std::uint16_t start,
                                    std::span<const std::uint16_t> values, const ClientInfo& client);
  std::optional<Reply> write_sim(std::uint8_t fc, registers::Table table, std::uint16_t start,
                                 std::span<const std::uint16_t> values, const ClientInfo& client);
  struct SimWrite;
  ControlLoop::SimEdit sim_edit(std::shared_ptr<SimWrite> write) const;
  std::optional<Reply> sim_outcome(const SimWrite& write, bool shown);
  bool write_sim_later(std::span<const std::uint8_t> pdu, const ClientInfo& client, std::function<void(Reply)> done);
  void run_commands(const std::vector<registers::CommandRequest>& commands, const ClientInfo& client);
  void press_jog_buttons(const std::vector<registers::CommandRequest>& commands, const ClientInfo& client);
  void acknowledge_settings_lost(const ClientInfo& client);  // a reset's, when the engine will take it
  std::int64_t sim_raw(const registers::Register& reg, const Snapshot& snap) const;
  // Logs a refused write (warn: client, reason, register, the rule in words),
  // records it for status.refusal_count / last_refused_register /
  // last_refusal_reason / last_refused_write, and answers its exception.
  Reply refuse(std::uint8_t fc, const registers::Refusal& refusal, const ClientInfo& client);
  // The write path (modbus_service_write.cpp): a batch of writes decided in
  // turn and committed together.
  struct WriteTicket;
  struct LaterWrite;
  // True when it handed the control loop new settings without waking it.
  bool process_batch(const std::vector<WriteTicket*>& batch);
  // Under batch_mutex_ (held on entry and on return): decides and commits
  // the writes queued (or the reserved one alone), wakes the threads of
  // those that wait, passes the lead on, and answers those taken later.
  void lead(std::unique_lock<std::mutex>& lock, WriteTicket* reserved);
  void answer_later(LaterWrite& w);
  void run_writer();
  void carry_out(WriteTicket& t, WritePlan& plan, const std::string& owner, std::size_t staged);
  // Under batch_mutex_: the lead goes to the first write queued, woken alone
  // (the others sleep on until their own batch is done), or to nobody.
  void pass_lead();
  std::mutex batch_mutex_;
  std::vector<WriteTicket*> batch_queue_;  // under batch_mutex_
  bool batch_leader_ = false;              // under batch_mutex_: a thread decides and commits a batch
  // Under batch_mutex_: the thread handle_now() reserved the lead for (its
  // request alone makes the next batch).
  std::optional<std::thread::id> reserved_for_;
  // The settings writer: started with the first write taken later; leads
  // when the first write queued is one of those (under batch_mutex_).
  std::thread writer_;
  std::condition_variable writer_wake_;
  bool writer_leads_ = false;
  bool writer_stops_ = false;
  bool needs_nothing_durable(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client) const;
  // Under mutex_: the effects of an accepted plan (server/write_plan.hpp) and of a refused wrong code.
  void apply_effect(registers::Effect effect);
  void count_wrong_unlock_code(std::uint32_t code, const ClientInfo& client);
  void expire_edit_sessions();
  void unlock(std::uint32_t code, const ClientInfo& client);
  std::chrono::steady_clock::time_point now() const;

  static thread_local std::optional<registers::Refusal> refused_here_;  // refuse()'s last, for command()
  static thread_local std::optional<std::uint16_t> written_start_;  // the write request refuse() answers
  ServiceConfig config_;
  ControlLoop& loop_;
  persistence::SettingsStore* store_;
  // settings_, host_, extras_ and the store. Reads take it shared: the event
  // loops answer reads side by side, and one loop preempted inside a read
  // never holds up the other.
  mutable std::shared_mutex mutex_;
  bool may_write(const ClientInfo& client) const;
  homing::Settings settings_;
  bool locked_ = false;
  registers::HostRegisters host_{};
  JogButtons jog_buttons_;  // who holds which jog coil: host_.jog_plus/minus read back from it
  std::array<persistence::ChangeSource, homing::kAxisCount> position_set_by_{};  // under mutex_
  registers::StatusExtras extras_{};
  LineDiagnostics diagnostics_;
  // The last refused write: count (bits 0-15), register (16-31), reason (32-47).
  std::atomic<std::uint64_t> last_refusal_{0};
  UnlockGuard unlock_guard_;  // under mutex_
  EditSessions edits_;        // under mutex_
  std::mutex log_mutex_;      // refusal_log_ (refuse() runs with and without mutex_)
  RefusalLog refusal_log_;
};

}  // namespace server
