#include "modbus_service.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "registers/lookup.hpp"
#include "registers/sim_bindings.hpp"

namespace server {
namespace {

using registers::ExceptionCode;
using registers::Table;

constexpr std::uint8_t kReadCoils = 1, kReadDiscrete = 2, kReadHolding = 3, kReadInput = 4, kWriteCoil = 5,
                       kWriteRegister = 6, kWriteCoils = 15, kWriteRegisters = 16, kReadWrite = 23,
                       kReadFileRecord = 20, kEncapsulated = 43;

Reply fail(std::uint8_t fc, ExceptionCode code) { return exception_reply(fc, static_cast<std::uint8_t>(code)); }

Reply refusal_reply(std::uint8_t fc, const registers::Refusal& r, const ClientInfo& client) {
  spdlog::debug("{} {}: FC{} refused with exception {:02X} ({}): {}", client.transport, client.address, fc,
                static_cast<int>(r.code), registers::exception_name(r.code), r.message);
  return fail(fc, r.code);
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

}  // namespace

ModbusService::ModbusService(ServiceConfig config, ControlLoop& loop, persistence::SettingsStore* store,
                             const homing::Settings& settings)
    : config_(config), loop_(loop), store_(store), settings_(settings), locked_(config.unlock_code != 0) {
  extras_.settings_locked = locked_;
}

// RTU clients stand at the cabinet's serial line: the allow-list is for the network.
bool ModbusService::may_write(const ClientInfo& client) const {
  if (client.transport != "tcp" || config_.write_allow.empty()) return true;
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
  if (unit == config_.unit_id) return dispatch(Target::module, pdu, client, false);
  // The Modbus TCP implementation guide: a device addressed by its IP address
  // answers unit id 0xFF, and 0 is accepted for direct addressing too (many
  // clients and SCADA drivers send one of them by default).
  if (client.transport == "tcp" && (unit == 0xFF || unit == 0)) return dispatch(Target::module, pdu, client, false);
  if (config_.sim_unit_id && unit == *config_.sim_unit_id) return dispatch(Target::simulator, pdu, client, false);
  if (unit == 0 && client.transport == "rtu") {
    dispatch(Target::module, pdu, client, true);  // applied, never answered
    return Reply{};
  }
  // A unit id that does not exist here: over TCP the gateway answer "target
  // device failed to respond" (0x0B); over RTU silence, as on a shared bus.
  if (client.transport == "tcp") return exception_reply(pdu[0], 0x0B);
  return Reply{};
}

Reply ModbusService::dispatch(Target target, std::span<const std::uint8_t> pdu, const ClientInfo& client,
                              bool broadcast) {
  const std::uint8_t fc = pdu[0];
  auto bad_value = [&] { return fail(fc, ExceptionCode::illegal_data_value); };
  switch (fc) {
    case kReadCoils:
    case kReadDiscrete:
    case kReadHolding:
    case kReadInput: {
      if (broadcast) return Reply{};
      if (pdu.size() != 5) return bad_value();
      const std::uint16_t start = be16(pdu, 1), count = be16(pdu, 3);
      if (fc == kReadCoils || fc == kReadDiscrete) {
        if (count < 1 || count > 2000) return bad_value();
        return read_bits(target, fc, fc == kReadCoils ? Table::coil : Table::discrete_input, start, count);
      }
      if (count < 1 || count > 125) return bad_value();
      return read_registers(target, fc, fc == kReadHolding ? Table::holding_register : Table::input_register,
                            start, count);
    }
    case kWriteCoil: {
      if (pdu.size() != 5) return bad_value();
      const std::uint16_t start = be16(pdu, 1), value = be16(pdu, 3);
      if (value != 0xFF00 && value != 0x0000) return bad_value();
      const std::uint16_t bit = value == 0xFF00 ? 1 : 0;
      if (auto r = write(target, fc, Table::coil, start, std::span(&bit, 1), client)) return *r;
      return Reply{true, std::vector<std::uint8_t>(pdu.begin(), pdu.end())};
    }
    case kWriteRegister: {
      if (pdu.size() != 5) return bad_value();
      const std::uint16_t start = be16(pdu, 1), value = be16(pdu, 3);
      if (auto r = write(target, fc, Table::holding_register, start, std::span(&value, 1), client)) return *r;
      return Reply{true, std::vector<std::uint8_t>(pdu.begin(), pdu.end())};
    }
    case kWriteCoils: {
      if (pdu.size() < 6) return bad_value();
      const std::uint16_t start = be16(pdu, 1), count = be16(pdu, 3);
      const std::uint8_t bytes = pdu[5];
      if (count < 1 || count > 1968 || bytes != (count + 7) / 8 || pdu.size() != 6u + bytes) return bad_value();
      std::vector<std::uint16_t> bits(count);
      for (std::uint16_t i = 0; i < count; ++i) bits[i] = (pdu[6 + i / 8] >> (i % 8)) & 1;
      if (auto r = write(target, fc, Table::coil, start, bits, client)) return *r;
      Reply ok{true, {fc}};
      put16(ok.pdu, start);
      put16(ok.pdu, count);
      return ok;
    }
    case kWriteRegisters: {
      if (pdu.size() < 6) return bad_value();
      const std::uint16_t start = be16(pdu, 1), count = be16(pdu, 3);
      const std::uint8_t bytes = pdu[5];
      if (count < 1 || count > 123 || bytes != count * 2 || pdu.size() != 6u + bytes) return bad_value();
      std::vector<std::uint16_t> words(count);
      for (std::uint16_t i = 0; i < count; ++i) words[i] = be16(pdu, 6 + 2 * i);
      if (auto r = write(target, fc, Table::holding_register, start, words, client)) return *r;
      Reply ok{true, {fc}};
      put16(ok.pdu, start);
      put16(ok.pdu, count);
      return ok;
    }
    case kReadWrite: {
      if (pdu.size() < 10) return bad_value();
      const std::uint16_t read_start = be16(pdu, 1), read_count = be16(pdu, 3);
      const std::uint16_t write_start = be16(pdu, 5), write_count = be16(pdu, 7);
      const std::uint8_t bytes = pdu[9];
      if (read_count < 1 || read_count > 125 || write_count < 1 || write_count > 121 || bytes != write_count * 2 ||
          pdu.size() != 10u + bytes)
        return bad_value();
      // The read range must be valid too before anything is written.
      if (Reply probe = read_registers(target, fc, Table::holding_register, read_start, read_count);
          probe.pdu.size() == 2 && (probe.pdu[0] & 0x80))
        return probe;
      std::vector<std::uint16_t> words(write_count);
      for (std::uint16_t i = 0; i < write_count; ++i) words[i] = be16(pdu, 10 + 2 * i);
      if (auto r = write(target, fc, Table::holding_register, write_start, words, client)) return *r;
      if (broadcast) return Reply{};
      return read_registers(target, fc, Table::holding_register, read_start, read_count);
    }
    case kEncapsulated:
      if (broadcast) return Reply{};
      return device_identification(pdu);
    case kReadFileRecord:
      if (broadcast || target != Target::module) return broadcast ? Reply{} : fail(fc, ExceptionCode::illegal_function);
      return read_file_record(pdu);
    default:
      spdlog::debug("{} {}: function code {} not supported: exception 01", client.transport, client.address, fc);
      if (broadcast) return Reply{};
      return fail(fc, ExceptionCode::illegal_function);
  }
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

Reply ModbusService::read_registers(Target target, std::uint8_t fc, Table table, std::uint16_t start,
                                    std::uint16_t count) {
  std::vector<std::uint16_t> words(count);
  const Snapshot snap = loop_.snapshot();
  std::optional<registers::Refusal> refused;
  if (target == Target::module) {
    std::lock_guard lock(mutex_);
    const registers::ModuleView view{settings_, host_, snap.status, extras_};
    refused = registers::read_module_words(table, start, words, config_.word_order, view);
  } else {
    refused = registers::read_words(registers::Unit::simulator, table, start, words, config_.word_order,
                                    [&](const registers::Register& r) { return sim_raw(r, snap); });
  }
  if (refused) return fail(fc, refused->code);
  Reply reply{true, {fc, static_cast<std::uint8_t>(count * 2)}};
  reply.pdu.reserve(2 + count * 2u);
  for (std::uint16_t w : words) put16(reply.pdu, w);
  return reply;
}

Reply ModbusService::read_bits(Target target, std::uint8_t fc, Table table, std::uint16_t start,
                               std::uint16_t count) {
  std::vector<std::uint8_t> bits(count);
  const Snapshot snap = loop_.snapshot();
  std::optional<registers::Refusal> refused;
  if (target == Target::module) {
    std::lock_guard lock(mutex_);
    const registers::ModuleView view{settings_, host_, snap.status, extras_};
    refused = registers::read_module_bits(table, start, bits, view);
  } else {
    refused = registers::read_bits(registers::Unit::simulator, table, start, bits,
                                   [&](const registers::Register& r) { return sim_raw(r, snap); });
  }
  if (refused) return fail(fc, refused->code);
  const std::size_t nbytes = (count + 7u) / 8u;
  Reply reply{true, {fc, static_cast<std::uint8_t>(nbytes)}};
  reply.pdu.resize(2 + nbytes, 0);
  for (std::size_t i = 0; i < count; ++i)
    if (bits[i]) reply.pdu[2 + i / 8] |= static_cast<std::uint8_t>(1u << (i % 8));
  return reply;
}

std::optional<Reply> ModbusService::write(Target target, std::uint8_t fc, Table table, std::uint16_t start,
                                          std::span<const std::uint16_t> values, const ClientInfo& client) {
  if (!may_write(client)) {
    spdlog::warn("{} {}: write refused, the address is not in --write-allow (exception 01)", client.transport,
                 client.address);
    return fail(fc, ExceptionCode::illegal_function);
  }
  if (target == Target::module) return write_module(fc, table, start, values, client);
  return write_sim(fc, table, start, values, client);
}

std::optional<Reply> ModbusService::write_module(std::uint8_t fc, Table table, std::uint16_t start,
                                                 std::span<const std::uint16_t> values, const ClientInfo& client) {
  std::vector<registers::CommandRequest> commands;
  {
    std::lock_guard lock(mutex_);
    auto accepted = registers::validate_write(table, start, values, config_.word_order, settings_, host_);
    if (!accepted) return refusal_reply(fc, accepted.error(), client);
    if (accepted->host.unlock_code != 0) {
      const bool right = config_.unlock_code != 0 && accepted->host.unlock_code == config_.unlock_code;
      accepted->host.unlock_code = 0;
      if (!right) {
        spdlog::warn("{} {}: wrong unlock code written to security.unlock (exception 03); settings stay locked",
                     client.transport, client.address);
        return fail(fc, ExceptionCode::illegal_data_value);
      }
      if (locked_) spdlog::info("settings unlocked by {} {}", client.transport, client.address);
      locked_ = false;
      extras_.settings_locked = false;
    }
    if (accepted->changes_persisted()) {
      if (locked_) {
        spdlog::warn("{} {}: settings write refused, settings are locked (exception 04): {}", client.transport,
                     client.address, describe_changes(accepted->changes));
        return fail(fc, ExceptionCode::server_device_failure);
      }
      if (config_.machine_check) {
        if (auto problem = config_.machine_check(accepted->settings)) {
          spdlog::warn("{} {}: settings write refused, the machine's wiring cannot do it (exception 03): {}; {}",
                       client.transport, client.address, *problem, describe_changes(accepted->changes));
          return fail(fc, ExceptionCode::illegal_data_value);
        }
      }
      if (loop_.snapshot().status.homing) {
        spdlog::warn("{} {}: settings write refused while a homing cycle runs (exception 06): {}",
                     client.transport, client.address, describe_changes(accepted->changes));
        return fail(fc, ExceptionCode::server_device_busy);
      }
      std::vector<persistence::SettingWrite> writes;
      for (const auto& c : accepted->changes)
        if (c.reg->persisted) writes.push_back({c.reg->name(), c.new_raw});
      if (store_) {
        auto committed = store_->commit(writes, persistence::ChangeSource{client.transport, client.address});
        if (!committed) {
          spdlog::error("{} {}: settings not stored, answered exception 04: {}", client.transport, client.address,
                        committed.error().message);
          return fail(fc, ExceptionCode::server_device_failure);
        }
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
      case Command::abort: c.abort = true; any = true; break;
      case Command::reset_alarm:
        c.reset_alarm = true;
        any = true;
        if (store_ && store_->settings_lost()) {
          std::lock_guard lock(mutex_);
          (void)store_->acknowledge_settings_lost(persistence::ChangeSource{client.transport, client.address});
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
    spdlog::info("command from {} {}: {}{}{}", client.transport, client.address, command_name(r.command),
                 r.axis >= 0 ? "." + std::string(homing::kAxisLetters[a]) : std::string(),
                 held ? (r.on ? " on" : " off") : "");
  }
  if (any) loop_.submit(c, true);
}

std::optional<Reply> ModbusService::write_sim(std::uint8_t fc, Table table, std::uint16_t start,
                                              std::span<const std::uint16_t> values, const ClientInfo& client) {
  // Address, access and range need no machine: refused here at once.
  if (auto decoded = registers::decode_write(registers::Unit::simulator, table, start, values, config_.word_order);
      !decoded)
    return refusal_reply(fc, decoded.error(), client);
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
  if (!loop_.edit_sim(edit, std::chrono::seconds(2))) {
    spdlog::warn("{} {}: simulator write not taken by the control loop in time (exception 06)", client.transport,
                 client.address);
    return fail(fc, ExceptionCode::server_device_busy);
  }
  if (refused) return refusal_reply(fc, *refused, client);
  if (busy_axis >= 0) {
    spdlog::info("{} {}: simulator write to sim.{}.* refused while that carriage moves (exception 06)",
                 client.transport, client.address, homing::kAxisLetters[static_cast<std::size_t>(busy_axis)]);
    return fail(fc, ExceptionCode::server_device_busy);
  }
  if (!changes.empty())
    spdlog::info("simulator changed by {} {}: {}", client.transport, client.address, describe_changes(changes));
  return std::nullopt;
}

// FC 20: the homing traces, one file per axis (see server/trace.hpp).
Reply ModbusService::read_file_record(std::span<const std::uint8_t> pdu) {
  constexpr std::uint8_t fc = kReadFileRecord;
  if (pdu.size() < 2) return fail(fc, ExceptionCode::illegal_data_value);
  const std::uint8_t bytes = pdu[1];
  if (bytes < 7 || bytes > 0xF5 || bytes % 7 != 0 || pdu.size() != 2u + bytes)
    return fail(fc, ExceptionCode::illegal_data_value);
  Reply reply{true, {fc, 0}};
  std::array<std::optional<std::vector<std::uint16_t>>, homing::kAxisCount> files;
  for (std::size_t at = 2; at < pdu.size(); at += 7) {
    const std::uint8_t type = pdu[at];
    const std::uint16_t file = be16(pdu, at + 1), record = be16(pdu, at + 3), length = be16(pdu, at + 5);
    if (type != 6 || file < 1 || file > homing::kAxisCount || record > 9999 || length < 1)
      return fail(fc, ExceptionCode::illegal_data_address);
    auto& words = files[file - 1u];
    if (!words) words = trace_file(loop_.trace(file - 1u));
    if (std::size_t{record} + length > words->size()) return fail(fc, ExceptionCode::illegal_data_address);
    if (reply.pdu.size() + 2u + 2u * length > kMaxPdu) return fail(fc, ExceptionCode::illegal_data_value);
    reply.pdu.push_back(static_cast<std::uint8_t>(1 + 2 * length));
    reply.pdu.push_back(6);
    for (std::uint16_t i = 0; i < length; ++i) put16(reply.pdu, (*words)[record + i]);
  }
  reply.pdu[1] = static_cast<std::uint8_t>(reply.pdu.size() - 2);
  return reply;
}

// FC 43 / MEI 14: libmodbus 3.1.6 has none, so it is answered here.
Reply ModbusService::device_identification(std::span<const std::uint8_t> pdu) {
  constexpr std::uint8_t fc = kEncapsulated;
  if (pdu.size() != 4 || pdu[1] != 0x0E) return fail(fc, ExceptionCode::illegal_function);
  const std::uint8_t code = pdu[2];
  std::uint8_t object = pdu[3];
  static constexpr std::array<std::string_view, 7> kObjects{
      "Homing Module Works", "HM-6", "0.1.0", "https://example.invalid/homing-module", "Homing module",
      "HM-6 Modbus homing controller", "homingd"};
  if (code < 1 || code > 4) return fail(fc, ExceptionCode::illegal_data_value);
  const std::uint8_t last = code == 1 ? 2 : 6;  // basic: 0..2; regular: 0..6 (no extended objects)
  if (code == 4) {
    if (object > 6) return fail(fc, ExceptionCode::illegal_data_address);
  } else if (object > last) {
    object = 0;  // stream access from an unknown object restarts at 0
  }
  Reply reply{true, {fc, 0x0E, code, 0x82 /* regular, stream and individual */, 0x00, 0x00, 0x00}};
  std::uint8_t count = 0;
  const std::uint8_t first = object, stop = code == 4 ? object : last;
  for (std::uint8_t id = first; id <= stop; ++id) {
    const auto text = kObjects[id];
    reply.pdu.push_back(id);
    reply.pdu.push_back(static_cast<std::uint8_t>(text.size()));
    reply.pdu.insert(reply.pdu.end(), text.begin(), text.end());
    ++count;
  }
  reply.pdu[6] = count;
  return reply;
}

}  // namespace server
