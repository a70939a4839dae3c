#include "modbus_service.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "client_role.hpp"
#include "device_identification.hpp"
#include "file_record.hpp"
#include "registers/lookup.hpp"
#include "write_log.hpp"
#include "write_plan.hpp"

namespace server {
namespace {

using registers::ExceptionCode;
using registers::Table;

Reply fail(std::uint8_t fc, ExceptionCode code) { return exception_reply(fc, static_cast<std::uint8_t>(code)); }

}  // namespace

thread_local std::optional<registers::Refusal> ModbusService::refused_here_;
thread_local std::optional<std::uint16_t> ModbusService::written_start_;

Reply ModbusService::refuse(std::uint8_t fc, const registers::Refusal& r, const ClientInfo& client) {
  refused_here_ = r;
  const auto level = r.reason == registers::RefusalReason::storage_failed ? spdlog::level::err : spdlog::level::warn;
  const std::string reason =
      fmt::format("reason {} ({})", r.reason_code(),
                  r.reason == registers::RefusalReason::rule ? homing::name_of(r.rule) : homing::name_of(r.reason));
  const std::string line =
      fmt::format("{} {}: write refused with exception {:02X} ({}), {} at address {}: {}", client.transport,
                  client.address, static_cast<int>(r.code), registers::exception_name(r.code), reason, r.address,
                  r.message);
  // Counted per client address (not per connection: a client that reconnects
  // is the same client) and certificate.
  const std::string who = fmt::format("{} {}{}{}", client.transport, client.address.substr(0, client.address.rfind(':')),
                                      client.identity.empty() ? "" : " ", client.identity);
  {
    std::lock_guard lock(log_mutex_);
    refusal_log_.refused(who, reason, level, line, now());
  }
  // Count, registers and reason of one refusal in one word, so that a read
  // never pairs the count of one refusal with the reason of another.
  const std::uint16_t written = written_start_.value_or(r.address);
  std::uint64_t old = last_refusal_.load();
  std::uint64_t next = 0;
  do {
    const std::uint64_t count = (old + 1) & 0xFFFF;
    next = count | (std::uint64_t{r.address} << 16) | (std::uint64_t{r.reason_code()} << 32) |
           (std::uint64_t{written} << 48);
  } while (!last_refusal_.compare_exchange_weak(old, next));
  return fail(fc, r.code);
}

ModbusService::~ModbusService() {
  {
    std::lock_guard lock(batch_mutex_);
    writer_stops_ = true;
  }
  writer_wake_.notify_one();
  if (writer_.joinable()) writer_.join();
  std::lock_guard lock(log_mutex_);
  refusal_log_.flush_all(now());
}

void ModbusService::flush_refusal_log() {
  std::lock_guard lock(log_mutex_);
  refusal_log_.flush(now());
}

std::chrono::steady_clock::time_point ModbusService::now() const {
  return config_.clock ? config_.clock() : std::chrono::steady_clock::now();
}

ModbusService::ModbusService(ServiceConfig config, ControlLoop& loop, persistence::SettingsStore* store,
                             const homing::Settings& settings)
    : config_(config),
      loop_(loop),
      store_(store),
      settings_(settings),
      locked_(config.unlock_code != 0),
      unlock_guard_(config.unlock_code, config.unlock_policy),
      refusal_log_("writes", config.refusal_log_interval,
                   [](spdlog::level::level_enum level, const std::string& line) { spdlog::log(level, "{}", line); }) {
  extras_.settings_locked = locked_;
}

// RTU clients stand at the cabinet's serial line: the allow-list is for the network.
bool ModbusService::may_write(const ClientInfo& client) const {
  if (!over_network(client.transport) || config_.write_allow.empty()) return true;
  return std::any_of(config_.write_allow.begin(), config_.write_allow.end(),
                     [&](const Cidr& c) { return c.contains(client.address); });
}

homing::Settings ModbusService::settings() const {
  std::shared_lock lock(mutex_);
  return settings_;
}

void ModbusService::set_extras(const registers::StatusExtras& extras) {
  std::lock_guard lock(mutex_);
  const bool locked = extras_.settings_locked;
  extras_ = extras;
  extras_.settings_locked = locked;  // owned here, not by the monitor
}

bool ModbusService::release_jogs_locked(const ClientInfo& client) {
  const homing::AxisMask released = jog_buttons_.disconnected(client.id);
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    if (!(released & homing::axis_bit(a))) continue;
    host_.jog_plus[a] = jog_buttons_.held(a, 1);
    host_.jog_minus[a] = jog_buttons_.held(a, -1);
    loop_.set_jog(a, 0, client.id);  // the loop's mailbox lock, never held while taking this one
  }
  return released != 0;
}

bool ModbusService::release_jogs(const ClientInfo& client) {
  std::unique_lock lock(mutex_);
  return release_jogs_locked(client);
}

void ModbusService::disconnected(const ClientInfo& client) {
  // A jog moves only while every client that holds it is there to stop it.
  std::unique_lock lock(mutex_);
  release_jogs_locked(client);
  // An edit session ends with its connection, as a transaction does.
  const std::string owner = EditSessions::owner_of(client);
  if (edits_.state(owner) == EditState::open)
    spdlog::info("edit session of {} discarded: the connection closed before its commit ({} staged settings not "
                 "applied)",
                 owner, edits_.staged_count(owner));
  edits_.close(owner);
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

bool ModbusService::module_unit(std::uint8_t unit, bool network) const {
  // The Modbus TCP implementation guide: a device addressed by its IP address
  // answers unit id 0xFF, and 0 is accepted for direct addressing too (many
  // clients and SCADA drivers send one of them by default).
  return unit == config_.unit_id || (network && (unit == 0xFF || unit == 0));
}

Reply ModbusService::route(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client) {
  const bool tcp = over_network(client.transport);
  if (module_unit(unit, tcp)) return dispatch(Target::module, pdu, client);
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

namespace {

// What is wrong with a write request the decoder refused with 03, for the
// refusal registers and the log; nothing for another function or exception.
std::optional<registers::Refusal> malformed_write(std::span<const std::uint8_t> pdu, ExceptionCode code) {
  if (code != ExceptionCode::illegal_data_value || pdu.empty()) return std::nullopt;
  const auto fc = static_cast<FunctionCode>(pdu[0]);
  const auto word = [&](std::size_t at) -> std::uint16_t {
    return pdu.size() >= at + 2 ? static_cast<std::uint16_t>((pdu[at] << 8) | pdu[at + 1]) : 0;
  };
  std::string what;
  std::uint16_t start = word(1);
  std::uint16_t quantity = 0;
  switch (fc) {
    case FunctionCode::write_single_coil:
      what = fmt::format("coil value {:04X}, which is neither FF00 (on) nor 0000 (off)", word(3));
      quantity = 1;
      break;
    case FunctionCode::write_single_register: what = "a request of the wrong length"; quantity = 1; break;
    case FunctionCode::write_multiple_coils:
    case FunctionCode::write_multiple_registers:
      quantity = word(3);
      what = fmt::format("quantity {} with byte count {} in a request of {} bytes", quantity,
                         pdu.size() > 5 ? pdu[5] : 0, pdu.size());
      break;
    case FunctionCode::read_write_registers:
      start = word(5);
      quantity = word(7);
      what = fmt::format("read quantity {}, write quantity {} with byte count {}", word(3), quantity,
                         pdu.size() > 9 ? pdu[9] : 0);
      break;
    default: return std::nullopt;
  }
  const auto reason = quantity == 0 && fc != FunctionCode::write_single_coil ? registers::RefusalReason::empty
                                                                              : registers::RefusalReason::malformed_write;
  return registers::Refusal::because(reason, start,
                                     fmt::format("function {}: {}; nothing was written", static_cast<int>(fc), what));
}

}  // namespace

Reply ModbusService::dispatch(Target target, std::span<const std::uint8_t> pdu, const ClientInfo& client) {
  const std::uint8_t fc = pdu[0];
  // The traces, the line diagnostics and the identity are the module's: the
  // simulator unit has none.
  if ((fc == static_cast<std::uint8_t>(FunctionCode::read_file_record) ||
       fc == static_cast<std::uint8_t>(FunctionCode::diagnostics) ||
       fc == static_cast<std::uint8_t>(FunctionCode::report_server_id) ||
       fc == static_cast<std::uint8_t>(FunctionCode::encapsulated_interface)) &&
      target != Target::module)
    return fail(fc, ExceptionCode::illegal_function);
  const auto request = decode_request(pdu);
  if (!request) {
    if (request.error() == ExceptionCode::illegal_function)
      spdlog::debug("{} {}: function code {} not supported: exception 01", client.transport, client.address, fc);
    // A write refused for its form is a refused write like any other:
    // counted, published and logged (per client and reason, not per request).
    if (const auto refusal = malformed_write(pdu, request.error())) return refuse(fc, *refusal, client);
    return fail(fc, request.error());
  }
  return apply(target, *request, client);
}

Reply ModbusService::apply(Target target, const Request& request, const ClientInfo& client) {
  const auto fc = static_cast<std::uint8_t>(request.function);
  if (const auto* r = std::get_if<ReadRequest>(&request.body)) return read(target, fc, *r, client);
  if (const auto* w = std::get_if<WriteRequest>(&request.body)) {
    if (auto refused = write(target, fc, *w, client)) return *refused;
    return accepted_write_reply(request.function, *w);
  }
  if (const auto* rw = std::get_if<ReadWriteRequest>(&request.body)) {
    // The read range must be valid too before anything is written.
    if (Reply probe = read(target, fc, rw->read, client); probe.pdu.size() == 2 && (probe.pdu[0] & 0x80)) return probe;
    if (auto refused = write(target, fc, rw->write, client)) return *refused;
    return read(target, fc, rw->read, client);
  }
  if (const auto* f = std::get_if<FileRecordRequest>(&request.body))
    return read_trace_records(*f, [this](std::size_t axis) { return trace_file(loop_.trace(axis)); });
  if (const auto* d = std::get_if<DiagnosticsRequest>(&request.body)) return diagnostics_.answer(client.transport, *d);
  if (std::holds_alternative<ReportServerIdRequest>(request.body))
    return report_server_id(config_.unit_id, config_.identity);
  return device_identification(std::get<DeviceIdRequest>(request.body), config_.identity);
}

Reply ModbusService::accepted_write_reply(FunctionCode function, const WriteRequest& w) {
  const auto fc = static_cast<std::uint8_t>(function);
  if (function == FunctionCode::write_single_coil) return echo_reply(fc, w.start, w.values[0] ? 0xFF00 : 0x0000);
  if (function == FunctionCode::write_single_register) return echo_reply(fc, w.start, w.values[0]);
  return quantity_reply(fc, w.start, static_cast<std::uint16_t>(w.values.size()));
}

registers::StatusExtras ModbusService::extras_now() const {
  registers::StatusExtras extras = extras_;
  const std::uint64_t refusal = last_refusal_.load();
  extras.refusal_count = static_cast<std::uint16_t>(refusal & 0xFFFF);
  extras.last_refused_register = static_cast<std::uint16_t>((refusal >> 16) & 0xFFFF);
  extras.last_refusal_reason = static_cast<std::uint16_t>((refusal >> 32) & 0xFFFF);
  extras.last_refused_write = static_cast<std::uint16_t>((refusal >> 48) & 0xFFFF);
  extras.unlock_lockout_s = static_cast<std::uint16_t>(std::min<std::int64_t>(unlock_guard_.remaining(now()).count(), 0xFFFF));
  extras.wrong_unlock_codes = static_cast<std::uint16_t>(std::min<std::uint32_t>(unlock_guard_.wrong_in_a_row(), 0xFFFF));
  return extras;
}

void ModbusService::with_module_view(const std::function<void(const registers::ModuleView&)>& use) {
  const homing::Status status = loop_.status();
  std::shared_lock lock(mutex_);
  const registers::StatusExtras extras = extras_now();
  use(registers::ModuleView{settings_, host_, status, extras});
}

Reply ModbusService::read(Target target, std::uint8_t fc, const ReadRequest& r, const ClientInfo& client) {
  const bool bits = r.table == Table::coil || r.table == Table::discrete_input;
  std::vector<std::uint16_t> words(bits ? 0 : r.count);
  std::vector<std::uint8_t> flags(bits ? r.count : 0);
  std::optional<registers::Refusal> refused;
  if (target == Target::module) {
    const homing::Status status = loop_.status();
    std::shared_lock lock(mutex_);
    registers::StatusExtras extras = extras_now();
    extras.edit_state = static_cast<std::uint16_t>(EditState::none);
    extras.edit_staged = 0;
    if (!edits_.empty()) {  // most reads: no client has a session, so no owner to name
      const std::string owner = EditSessions::owner_of(client);
      extras.edit_state = static_cast<std::uint16_t>(edits_.state(owner));
      extras.edit_staged = static_cast<std::uint16_t>(std::min<std::size_t>(edits_.staged_count(owner), 0xFFFF));
    }
    const registers::ModuleView view{settings_, host_, status, extras};
    refused = bits ? registers::read_module_bits(r.table, r.start, flags, view)
                   : registers::read_module_words(r.table, r.start, words, config_.word_order, view);
  } else {
    const Snapshot snap = loop_.snapshot();
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
  // What the client wrote, beside what a refusal is about (a rule may name another setting).
  struct WrittenStart {
    explicit WrittenStart(std::uint16_t start) { written_start_ = start; }
    ~WrittenStart() { written_start_.reset(); }
  } const written_start(w.start);
  if (target == Target::module) return write_module(fc, w.table, w.start, w.values, client);
  if (auto r = client_refusal(registers::Unit::simulator, w.table, w.start, w.values.size(), client, may_write(client)))
    return refuse(fc, *r, client);
  return write_sim(fc, w.table, w.start, w.values, client);
}

}  // namespace server
