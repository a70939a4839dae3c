#include "modbus_service.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "client_role.hpp"
#include "device_identification.hpp"
#include "file_record.hpp"
#include "registers/lookup.hpp"
#include "registers/sim_bindings.hpp"

namespace server {
namespace {

using registers::ExceptionCode;
using registers::Table;

Reply fail(std::uint8_t fc, ExceptionCode code) { return exception_reply(fc, static_cast<std::uint8_t>(code)); }

// Who changed a setting, for the audit log: over TLS also the certificate's subject and role.
persistence::ChangeSource source_of(const ClientInfo& client) {
  return persistence::ChangeSource{std::string(transport_name(client.transport)),
                                   client.identity.empty() ? client.address : client.address + " " + client.identity};
}

std::string_view command_name(registers::Command c) {
  using registers::Command;
  switch (c) {
    case Command::home_all: return "home_all";
    case Command::home_axis: return "home";
    case Command::abort: return "abort";
    case Command::reset_alarm: return "reset_alarm";
    case Command::jog_plus: return "jog_plus";
    case Command::jog_minus: return "jog_minus";
    case Command::move: return "move";
    case Command::homing_permit: return "homing_permit";
    case Command::lock_settings: return "lock_settings";
    case Command::home_axes: return "home_axes";
  }
  return "?";
}

std::string describe_changes(const std::vector<registers::Change>& changes) {
  std::string out;
  for (const auto& c : changes) {
    if (!out.empty()) out += "; ";
    out += c.reg->name() + ": " + registers::format_value(*c.reg, c.old_raw) + " -> " +
           registers::format_value(*c.reg, c.new_raw);
  }
  return out;
}

// The address of the first register a refused write is about: the first
// value it changes, else the first register it names.
std::uint16_t first_address(const std::vector<registers::Change>& changes, std::uint16_t start) {
  return changes.empty() ? start : changes.front().reg->address;
}

}  // namespace

Reply ModbusService::refuse(std::uint8_t fc, const registers::Refusal& r, const ClientInfo& client) {
  const auto level = r.reason == registers::RefusalReason::storage_failed ? spdlog::level::err : spdlog::level::warn;
  spdlog::log(level, "{} {}: write refused with exception {:02X} ({}), reason {} ({}) at address {}: {}",
              client.transport, client.address, static_cast<int>(r.code), registers::exception_name(r.code),
              r.reason_code(),
              r.reason == registers::RefusalReason::rule ? homing::name_of(r.rule) : homing::name_of(r.reason),
              r.address, r.message);
  // Count, register and reason of one refusal in one word, so that a read
  // never pairs the count of one refusal with the reason of another.
  std::uint64_t old = last_refusal_.load();
  std::uint64_t next = 0;
  do {
    const std::uint64_t count = (old + 1) & 0xFFFF;
    next = count | (std::uint64_t{r.address} << 16) | (std::uint64_t{r.reason_code()} << 32);
  } while (!last_refusal_.compare_exchange_weak(old, next));
  return fail(fc, r.code);
}

ModbusService::ModbusService(ServiceConfig config, ControlLoop& loop, persistence::SettingsStore* store,
                             const homing::Settings& settings)
    : config_(config), loop_(loop), store_(store), settings_(settings), locked_(config.unlock_code != 0) {
  extras_.settings_locked = locked_;
}

// RTU clients stand at the cabinet's serial line: the allow-list is for the network.
bool ModbusService::may_write(const ClientInfo& client) const {
  if (!over_network(client.transport) || config_.write_allow.empty()) return true;
  return std::any_of(config_.write_allow.begin(), config_.write_allow.end(),
                     [&](const Cidr& c) { return c.contains(client.address); });
}

homing::Settings ModbusService::settings() const {
  std::lock_guard lock(mutex_);
  return settings_;
}

void ModbusService::set_extras(const registers::StatusExtras& extras) {
  std::lock_guard lock(mutex_);
  const bool locked = extras_.settings_locked;
  extras_ = extras;
  extras_.settings_locked = locked;  // owned here, not by the monitor
}

void ModbusService::disconnected(const ClientInfo& client) {
  // A jog moves only while its client is there to stop it.
  loop_.release_jogs(client.id);
}

Reply ModbusService::handle(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client) {
  if (pdu.empty()) return Reply{};
  // Over RTU a frame for a unit that is not here is another device's; over
  // TCP (plain or TLS) every request is this server's (it answers 0B for unknown units).
  const bool ours = over_network(client.transport) || unit == 0 || unit == config_.unit_id ||
                    (config_.sim_unit_id && unit == *config_.sim_unit_id);
  if (ours) diagnostics_.addressed(client.transport);
  Reply reply = route(unit, pdu, client);
  if (ours) diagnostics_.answered(client.transport, reply);
  return reply;
}

Reply ModbusService::route(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client) {
  const bool tcp = over_network(client.transport);
  if (unit == config_.unit_id) return dispatch(Target::module, pdu, client);
  // The Modbus TCP implementation guide: a device addressed by its IP address
  // answers unit id 0xFF, and 0 is accepted for direct addressing too (many
  // clients and SCADA drivers send one of them by default).
  if (tcp && (unit == 0xFF || unit == 0)) return dispatch(Target::module, pdu, client);
  if (config_.sim_unit_id && unit == *config_.sim_unit_id) return dispatch(Target::simulator, pdu, client);
  if (unit == 0 && !tcp) {
    // An RTU broadcast: a write is applied to the module, nothing is answered.
    if (auto request = decode_request(pdu); request && is_write(request->function))
      (void)apply(Target::module, *request, client);
    return Reply{};
  }
  // A unit id that does not exist here: over TCP the gateway answer "target
  // device failed to respond" (0x0B); over RTU silence, as on a shared bus.
  if (tcp) return fail(pdu[0], ExceptionCode::gateway_target_failed);
  return Reply{};
}

Reply ModbusService::dispatch(Target target, std::span<const std::uint8_t> pdu, const ClientInfo& client) {
  const std::uint8_t fc = pdu[0];
  // The traces, the line diagnostics and the identity are the module's: the
  // simulator unit has none.
  if ((fc == static_cast<std::uint8_t>(FunctionCode::read_file_record) ||
       fc == static_cast<std::uint8_t>(FunctionCode::diagnostics) ||
       fc == static_cast<std::uint8_t>(FunctionCode::report_server_id)) &&
      target != Target::module)
    return fail(fc, ExceptionCode::illegal_function);
  const auto request = decode_request(pdu);
  if (!request) {
    if (request.error() == ExceptionCode::illegal_function)
      spdlog::debug("{} {}: function code {} not supported: exception 01", client.transport, client.address, fc);
    return fail(fc, request.error());
  }
  return apply(target, *request, client);
}

Reply ModbusService::apply(Target target, const Request& request, const ClientInfo& client) {
  const auto fc = static_cast<std::uint8_t>(request.function);
  if (const auto* r = std::get_if<ReadRequest>(&request.body)) return read(target, fc, *r);
  if (const auto* w = std::get_if<WriteRequest>(&request.body)) {
    if (auto refused = write(target, fc, *w, client)) return *refused;
    if (request.function == FunctionCode::write_single_coil)
      return echo_reply(fc, w->start, w->values[0] ? 0xFF00 : 0x0000);
    if (request.function == FunctionCode::write_single_register) return echo_reply(fc, w->start, w->values[0]);
    return quantity_reply(fc, w->start, static_cast<std::uint16_t>(w->values.size()));
  }
  if (const auto* rw = std::get_if<ReadWriteRequest>(&request.body)) {
    // The read range must be valid too before anything is written.
    if (Reply probe = read(target, fc, rw->read); probe.pdu.size() == 2 && (probe.pdu[0] & 0x80)) return probe;
    if (auto refused = write(target, fc, rw->write, client)) return *refused;
    return read(target, fc, rw->read);
  }
  if (const auto* f = std::get_if<FileRecordRequest>(&request.body))
    return read_trace_records(*f, [this](std::size_t axis) { return trace_file(loop_.trace(axis)); });
  if (const auto* d = std::get_if<DiagnosticsRequest>(&request.body)) return diagnostics_.answer(client.transport, *d);
  if (std::holds_alternative<ReportServerIdRequest>(request.body))
    return report_server_id(config_.unit_id, config_.identity);
  return device_identification(std::get<DeviceIdRequest>(request.body), config_.identity);
}

namespace {

registers::SimReadback readback_of(const homing::sim::SimulatorView& sim) {
  registers::SimReadback r;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    r.actual_position_mm[a] = sim.axes[a].actual_position_mm;
    r.sensor[a] = sim.axes[a].sensor;
    r.at_hard_stop[a] = sim.axes[a].at_hard_stop;
    r.driven_by[a] = sim.axes[a].driven_by;
  }
  return r;
}

registers::SimSwitches switches_of(const homing::sim::SimulatorView& sim) {
  return registers::SimSwitches{sim.estop, sim.start_button};
}

}  // namespace

std::int64_t ModbusService::sim_raw(const registers::Register& reg, const Snapshot& snap) const {
  return registers::sim_raw(reg, snap.sim.config, switches_of(snap.sim), readback_of(snap.sim));
}

Reply ModbusService::read(Target target, std::uint8_t fc, const ReadRequest& r) {
  const Snapshot snap = loop_.snapshot();
  const bool bits = r.table == Table::coil || r.table == Table::discrete_input;
  std::vector<std::uint16_t> words(bits ? 0 : r.count);
  std::vector<std::uint8_t> flags(bits ? r.count : 0);
  std::optional<registers::Refusal> refused;
  if (target == Target::module) {
    std::lock_guard lock(mutex_);
    registers::StatusExtras extras = extras_;
    const std::uint64_t refusal = last_refusal_.load();
    extras.refusal_count = static_cast<std::uint16_t>(refusal & 0xFFFF);
    extras.last_refused_register = static_cast<std::uint16_t>((refusal >> 16) & 0xFFFF);
    extras.last_refusal_reason = static_cast<std::uint16_t>((refusal >> 32) & 0xFFFF);
    const registers::ModuleView view{settings_, host_, snap.status, extras};
    refused = bits ? registers::read_module_bits(r.table, r.start, flags, view)
                   : registers::read_module_words(r.table, r.start, words, config_.word_order, view);
  } else {
    const auto raw_of = [&](const registers::Register& reg) { return sim_raw(reg, snap); };
    refused = bits ? registers::read_bits(registers::Unit::simulator, r.table, r.start, flags, raw_of)
                   : registers::read_words(registers::Unit::simulator, r.table, r.start, words, config_.word_order,
                                           raw_of);
  }
  if (refused) return fail(fc, refused->code);
  return bits ? bits_reply(fc, flags) : registers_reply(fc, words);
}

std::optional<Reply> ModbusService::write(Target target, std::uint8_t fc, const WriteRequest& w,
                                          const ClientInfo& client) {
  if (!may_write(client))
    return refuse(fc,
                  registers::Refusal::because(registers::RefusalReason::client_read_only, w.start,
                                              fmt::format("{} is not in --write-allow; nothing was written",
                                                          client.address)),
                  client);
  const auto unit = target == Target::module ? registers::Unit::module : registers::Unit::simulator;
  if (auto refused = access_refusal(client, unit, w.table, w.start, w.values.size()))
    return refuse(fc,
                  registers::Refusal::because(registers::RefusalReason::role, w.start,
                                              *refused + "; nothing was written"),
                  client);
  if (target == Target::module) return write_module(fc, w.table, w.start, w.values, client);
  return write_sim(fc, w.table, w.start, w.values, client);
}

std::optional<Reply> ModbusService::write_module(std::uint8_t fc, Table table, std::uint16_t start,
                                                 std::span<const std::uint16_t> values, const ClientInfo& client) {
  std::vector<registers::CommandRequest> commands;
  {
    std::lock_guard lock(mutex_);
    auto accepted = registers::validate_write(table, start, values, config_.word_order, settings_, host_);
    if (!accepted) return refuse(fc, accepted.error(), client);
    if (auto refused = registers::refusal_now(*accepted, loop_.snapshot().status))
      return refuse(fc, *refused, client);
    if (accepted->host.unlock_code != 0) {
      const bool right = config_.unlock_code != 0 && accepted->host.unlock_code == config_.unlock_code;
      accepted->host.unlock_code = 0;
      if (!right) {
        const registers::Register* unlock = registers::find_register("security.unlock");
        return refuse(fc,
                      registers::Refusal::because(registers::RefusalReason::wrong_unlock_code,
                                                  unlock ? unlock->address : start,
                                                  "wrong unlock code written to security.unlock; settings stay locked"),
                      client);
      }
      if (locked_) spdlog::info("settings unlocked by {} {}", client.transport, client.address);
      locked_ = false;
      extras_.settings_locked = false;
    }
    if (accepted->changes_persisted()) {
      using registers::RefusalReason;
      const std::uint16_t about = first_address(accepted->changes, start);
      const std::string changes = describe_changes(accepted->changes);
      if (locked_)
        return refuse(fc,
                      registers::Refusal::because(RefusalReason::locked, about,
                                                  "settings are locked (write the unlock code to security.unlock): " +
                                                      changes),
                      client);
      if (config_.machine_check) {
        if (auto problem = config_.machine_check(accepted->settings))
          return refuse(fc,
                        registers::Refusal::because(RefusalReason::wiring, about,
                                                    "the machine's wiring cannot do it: " + *problem + "; " + changes),
                        client);
      }
      if (loop_.snapshot().status.homing)
        return refuse(
            fc, registers::Refusal::because(RefusalReason::busy, about, "a homing cycle runs: " + changes), client);
      std::vector<persistence::SettingWrite> writes;
      for (const auto& c : accepted->changes)
        if (c.reg->persisted) writes.push_back({c.reg->name(), c.new_raw});
      if (store_) {
        auto committed = store_->commit(writes, source_of(client));
        if (!committed)
          return refuse(fc,
                        registers::Refusal::because(RefusalReason::storage_failed, about,
                                                    "settings not stored: " + committed.error().message + "; " +
                                                        changes),
                        client);
      }
      const bool new_limit = accepted->settings.global.history_max_rows != settings_.global.history_max_rows;
      settings_ = accepted->settings;
      loop_.set_settings(settings_);
      if (new_limit && store_) {
        const auto rows = settings_.global.history_max_rows;
        if (auto r = store_->set_limits(rows, rows); !r)
          spdlog::warn("history limit not applied: {}", r.error().message);
      }
      spdlog::info("settings changed by {} {}: {}", client.transport, client.address,
                   describe_changes(accepted->changes));
    }
    const std::uint16_t old_heartbeat = host_.heartbeat;
    host_ = accepted->host;
    if (host_.heartbeat != old_heartbeat) loop_.heartbeat_written(host_.heartbeat);
    commands = std::move(accepted->commands);
  }
  run_commands(commands, client);
  return std::nullopt;
}

void ModbusService::run_commands(const std::vector<registers::CommandRequest>& commands, const ClientInfo& client) {
  using registers::Command;
  homing::Commands c{};
  bool any = false;
  for (const auto& r : commands) {
    const std::size_t a = r.axis >= 0 ? static_cast<std::size_t>(r.axis) : 0;
    switch (r.command) {
      case Command::home_all: c.home_all = true; any = true; break;
      case Command::home_axis: c.home_axes |= homing::axis_bit(a); any = true; break;
      case Command::home_axes: c.home_axes |= r.axes; any = true; break;
      case Command::abort: c.abort = true; any = true; break;
      case Command::reset_alarm:
        c.reset_alarm = true;
        any = true;
        if (store_ && store_->settings_lost()) {
          std::lock_guard lock(mutex_);
          (void)store_->acknowledge_settings_lost(source_of(client));
        }
        break;
      case Command::jog_plus: loop_.set_jog(a, r.on ? 1 : 0, client.id); break;
      case Command::jog_minus: loop_.set_jog(a, r.on ? -1 : 0, client.id); break;
      case Command::move: {
        std::lock_guard lock(mutex_);
        c.move_axes |= homing::axis_bit(a);
        c.move_target_mm[a] = host_.target_mm[a];
        any = true;
        break;
      }
      case Command::homing_permit: loop_.set_permit_coil(r.on); break;
      case Command::lock_settings: {
        std::lock_guard lock(mutex_);
        locked_ = config_.unlock_code != 0;
        extras_.settings_locked = locked_;
        break;
      }
    }
    const bool held = r.command == Command::jog_plus || r.command == Command::jog_minus ||
                      r.command == Command::homing_permit;
    std::string axes = r.axis >= 0 ? "." + std::string(homing::kAxisLetters[a]) : std::string();
    for (std::size_t n = 0; n < homing::kAxisCount; ++n)
      if (r.axes & homing::axis_bit(n)) axes += " " + std::string(homing::kAxisLetters[n]);
    spdlog::info("command from {} {}: {}{}{}", client.transport, client.address, command_name(r.command), axes,
                 held ? (r.on ? " on" : " off") : "");
  }
  if (any) loop_.submit(c, true);
}

std::optional<Reply> ModbusService::write_sim(std::uint8_t fc, Table table, std::uint16_t start,
                                              std::span<const std::uint16_t> values, const ClientInfo& client) {
  // Address, access and range need no machine: refused here at once.
  if (auto decoded = registers::decode_write(registers::Unit::simulator, table, start, values, config_.word_order);
      !decoded)
    return refuse(fc, decoded.error(), client);
  // The rest is decided and applied on the live simulator inside the control
  // loop (never on a snapshot that may miss the previous write), and answered
  // once a snapshot shows it: an acknowledged write holds and reads back.
  std::optional<registers::Refusal> refused;
  int busy_axis = -1;
  std::vector<registers::Change> changes;
  const ControlLoop::SimEdit edit = [&](homing::sim::SimulatorControls& sim, const homing::Outputs& next) {
    const homing::sim::SimulatorView now = sim.view();
    auto accepted = registers::validate_sim_write(table, start, values, config_.word_order, now.config,
                                                  switches_of(now), readback_of(now));
    if (!accepted) {
      refused = accepted.error();
      return;
    }
    const registers::AcceptedSimWrite& w = *accepted;
    // A carriage that moves (or is about to) is not touched at all.
    for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
      if (w.axes_written[a] && sim.in_motion(a, next)) {
        busy_axis = static_cast<int>(a);
        return;
      }
    }
    for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
      if (!w.axes_written[a]) continue;
      sim.set_axis_config(a, w.config.axes[a]);
      if (w.placed[a]) sim.place(a, w.config.axes[a].actual_position_mm);
      if (w.lose_steps_mm[a] != 0) sim.lose_steps(a, w.lose_steps_mm[a]);
    }
    if (w.seed_written) sim.set_seed(w.config.seed);
    sim.set_estop(w.switches.estop);
    sim.set_start_button(w.switches.start_button);
    changes = w.changes;
  };
  using registers::RefusalReason;
  if (!loop_.edit_sim(edit, std::chrono::seconds(2)))
    return refuse(fc,
                  registers::Refusal::because(RefusalReason::loop_not_responding, start,
                                              "the control loop did not take the simulator write in time"),
                  client);
  if (refused) return refuse(fc, *refused, client);
  if (busy_axis >= 0)
    return refuse(fc,
                  registers::Refusal::because(RefusalReason::carriage_moving, start,
                                              fmt::format("sim.{}.* is not written while that carriage moves",
                                                          homing::kAxisLetters[static_cast<std::size_t>(busy_axis)])),
                  client);
  if (!changes.empty())
    spdlog::info("simulator changed by {} {}: {}", client.transport, client.address, describe_changes(changes));
  return std::nullopt;
}

}  // namespace server
